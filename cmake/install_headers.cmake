# Installs raypack's public headers, run by `cmake --install` (lib/CMakeLists.txt): the
# umbrella include/raypack/raypack.h and every repository header it includes, directly or not,
# go to <prefix>/<RP_INCLUDE_DIR>/raypack/ under their repository paths (core/scene.h ->
# raypack/core/scene.h), each `#include "path"` of a repository header rewritten to
# `#include "raypack/path"`. Consumers then need only <prefix>/include on their include path,
# and a header of theirs named like one of raypack's (base/math.h) is never picked up in its
# place.
#
# The installed set is the public API and nothing else, so it is listed (rp_public_headers)
# and checked against the includes: a public header that includes any other repository
# header, or a listed header that raypack.h no longer reaches, stops the install with a message
# naming both. Without the list an include added for an inline helper silently installed the
# helper's header and all it includes (the kernels' lane arithmetic, the RP_DCHECK of
# base/error.h) as API. A public header may include the standard library and other public
# headers only, so raypack's dependencies stay private to libraypack.so and the package finds
# none of them; and it defines no macro but RAYPACK_* ones (a macro reaches every consumer).
#
# Reads RP_SOURCE_DIR (the repository), RP_GENERATED_DIR (where the build made
# raypack/version.h from include/raypack/version.h.in), RP_STAGE_DIR (a scratch folder in the
# build tree) and RP_INCLUDE_DIR (relative to CMAKE_INSTALL_PREFIX, the prefix being installed
# to).

cmake_policy(PUSH)
cmake_policy(VERSION 3.25)  # install scripts start with old policies (IN_LIST, among others)
# The public headers by their paths under <prefix>/include/raypack/. A header joins when a
# program needs what it declares; a helper that public inline code needs belongs in the .cpp
# or in an internal header that a .cpp includes (render/camera_lanes.h).
set(rp_public_headers
    raypack.h
    version.h
    analysis/diff.h
    analysis/raygen.h
    analysis/reference.h
    backends/registry.h
    base/bbox.h
    base/error_type.h
    base/math.h
    base/strided.h
    core/affine.h
    core/backend.h
    core/geometry/intersection.h
    core/geometry/plane.h
    core/geometry/polygon.h
    core/geometry/quadric.h
    core/queries.h
    core/ray.h
    core/scene.h
    core/thread_limit.h
    io/loaders/animation.h
    io/loaders/load.h
    io/rayfile.h
    render/camera.h
    render/image_io.h
    render/render.h)
set(rp_installed "")
set(rp_queue "${RP_SOURCE_DIR}/include/raypack/raypack.h")
set(rp_headers "")
file(REMOVE_RECURSE "${RP_STAGE_DIR}")
while(rp_queue)
  list(POP_FRONT rp_queue rp_header)
  if(rp_header IN_LIST rp_headers)
    continue()
  endif()
  list(APPEND rp_headers ${rp_header})
  # Its path under <prefix>/include/raypack/ (the first of these folders it lies in), and the
  # name the messages give it.
  foreach(rp_root "${RP_SOURCE_DIR}/include/raypack/" "${RP_GENERATED_DIR}/raypack/" "${RP_SOURCE_DIR}/")
    string(LENGTH "${rp_root}" rp_length)
    string(SUBSTRING "${rp_header}" 0 ${rp_length} rp_head)
    if(rp_head STREQUAL rp_root)
      string(SUBSTRING "${rp_header}" ${rp_length} -1 rp_path)
      break()
    endif()
  endforeach()
  file(RELATIVE_PATH rp_name "${RP_SOURCE_DIR}" "${rp_header}")
  list(APPEND rp_installed ${rp_path})
  file(READ "${rp_header}" rp_text)
  file(STRINGS "${rp_header}" rp_lines REGEX "^[ \t]*#[ \t]*define[ \t]")
  foreach(rp_line IN LISTS rp_lines)
    string(REGEX REPLACE "^[ \t]*#[ \t]*define[ \t]+([A-Za-z0-9_]*).*" "\\1" rp_macro "${rp_line}")
    if(NOT rp_macro MATCHES "^RAYPACK_")
      message(FATAL_ERROR "${rp_name} defines ${rp_macro}: a public header defines no macro but RAYPACK_* ones, since "
                          "every consumer's code would see it; keep the macro in a header no public one includes "
                          "(as base/error.h keeps RP_CHECK and RP_DCHECK)")
    endif()
  endforeach()
  # The package finds no dependency for its consumers, so a public header may include the
  # standard library (names without '/' or '.') but no other library's header.
  file(STRINGS "${rp_header}" rp_lines REGEX "^[ \t]*#[ \t]*include[ \t]*<[^>]*[/.]")
  if(rp_lines)
    list(GET rp_lines 0 rp_line)
    message(FATAL_ERROR "${rp_name}: ${rp_line}: a public header includes another library's header, which "
                        "consumers of the installed package do not have")
  endif()
  file(STRINGS "${rp_header}" rp_lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
  foreach(rp_line IN LISTS rp_lines)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\".*" "\\1" rp_include "${rp_line}")
    # "raypack/..." is include/raypack's, or the build's made header; anything else is a path
    # from the repository's root, rewritten to lie under raypack/.
    if(rp_include MATCHES "^raypack/" AND EXISTS "${RP_SOURCE_DIR}/include/${rp_include}")
      set(rp_source "${RP_SOURCE_DIR}/include/${rp_include}")
    elseif(rp_include MATCHES "^raypack/")
      set(rp_source "${RP_GENERATED_DIR}/${rp_include}")
    else()
      set(rp_source "${RP_SOURCE_DIR}/${rp_include}")
      string(REPLACE "\"${rp_include}\"" "\"raypack/${rp_include}\"" rp_text "${rp_text}")
    endif()
    if(NOT EXISTS "${rp_source}")
      message(FATAL_ERROR "${rp_name} includes \"${rp_include}\", which is neither a header of include/ (or one the "
                          "build made there) nor one from the repository root: a public header may include only "
                          "those and the standard library")
    endif()
    string(REGEX REPLACE "^raypack/" "" rp_included "${rp_include}")
    if(NOT rp_included IN_LIST rp_public_headers)
      message(FATAL_ERROR "${rp_name} includes \"${rp_include}\", which is not a public header, so the install would "
                          "make it API: include it from the .cpp (or from an internal header only .cpp files include, "
                          "as render/camera_lanes.h), or, if programs are meant to use it, add ${rp_included} to "
                          "rp_public_headers in cmake/install_headers.cmake")
    endif()
    list(APPEND rp_queue "${rp_source}")
  endforeach()
  file(WRITE "${RP_STAGE_DIR}/raypack/${rp_path}" "${rp_text}")
endwhile()
foreach(rp_path IN LISTS rp_public_headers)
  if(NOT rp_path IN_LIST rp_installed)
    message(FATAL_ERROR "${rp_path} is in rp_public_headers (cmake/install_headers.cmake) but raypack.h no longer "
                        "includes it, directly or not: include it there, or take it off the list")
  endif()
endforeach()
file(INSTALL "${RP_STAGE_DIR}/raypack" DESTINATION "${CMAKE_INSTALL_PREFIX}/${RP_INCLUDE_DIR}")
cmake_policy(POP)
