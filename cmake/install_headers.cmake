# Installs raypack's public headers, run by `cmake --install` (lib/CMakeLists.txt): the
# umbrella include/raypack/raypack.h and every repository header it includes, directly or not,
# go to <prefix>/<RP_INCLUDE_DIR>/raypack/ under their repository paths (core/scene.h ->
# raypack/core/scene.h), each `#include "path"` of a repository header rewritten to
# `#include "raypack/path"`. Consumers then need only <prefix>/include on their include path,
# and a header of theirs named like one of raypack's (base/math.h) is never picked up in its
# place. The set is worked out at install time from the includes themselves, so a header
# added to the API is installed without a list to keep.
#
# A public header may include the standard library and other public headers only: raypack's
# dependencies stay private to libraypack.so, and the package finds none of them.
#
# Reads RP_SOURCE_DIR (the repository), RP_GENERATED_DIR (where the build made
# raypack/version.h from include/raypack/version.h.in), RP_STAGE_DIR (a scratch folder in the
# build tree) and RP_INCLUDE_DIR (relative to CMAKE_INSTALL_PREFIX, the prefix being installed
# to).

cmake_policy(PUSH)
cmake_policy(VERSION 3.25)  # install scripts start with old policies (IN_LIST, among others)
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
  file(READ "${rp_header}" rp_text)
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
    list(APPEND rp_queue "${rp_source}")
  endforeach()
  file(WRITE "${RP_STAGE_DIR}/raypack/${rp_path}" "${rp_text}")
endwhile()
file(INSTALL "${RP_STAGE_DIR}/raypack" DESTINATION "${CMAKE_INSTALL_PREFIX}/${RP_INCLUDE_DIR}")
cmake_policy(POP)
