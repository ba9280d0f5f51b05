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
# Reads RP_SOURCE_DIR (the repository), RP_STAGE_DIR (a scratch folder in the build tree) and
# RP_INCLUDE_DIR (relative to CMAKE_INSTALL_PREFIX, the prefix being installed to).

cmake_policy(PUSH)
cmake_policy(VERSION 3.25)  # install scripts start with old policies (IN_LIST, among others)
set(rp_queue include/raypack/raypack.h)
set(rp_headers "")
file(REMOVE_RECURSE "${RP_STAGE_DIR}")
while(rp_queue)
  list(POP_FRONT rp_queue rp_header)
  if(rp_header IN_LIST rp_headers)
    continue()
  endif()
  list(APPEND rp_headers ${rp_header})
  file(READ "${RP_SOURCE_DIR}/${rp_header}" rp_text)
  # The package finds no dependency for its consumers, so a public header may include the
  # standard library (names without '/' or '.') but no other library's header.
  file(STRINGS "${RP_SOURCE_DIR}/${rp_header}" rp_lines REGEX "^[ \t]*#[ \t]*include[ \t]*<[^>]*[/.]")
  if(rp_lines)
    list(GET rp_lines 0 rp_line)
    message(FATAL_ERROR "${rp_header}: ${rp_line}: a public header includes another library's header, which "
                        "consumers of the installed package do not have")
  endif()
  file(STRINGS "${RP_SOURCE_DIR}/${rp_header}" rp_lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
  foreach(rp_line IN LISTS rp_lines)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\".*" "\\1" rp_include "${rp_line}")
    if(rp_include MATCHES "^raypack/")
      set(rp_source include/${rp_include})
    else()
      set(rp_source ${rp_include})
      string(REPLACE "\"${rp_include}\"" "\"raypack/${rp_include}\"" rp_text "${rp_text}")
    endif()
    if(NOT EXISTS "${RP_SOURCE_DIR}/${rp_source}")
      message(FATAL_ERROR "${rp_header} includes \"${rp_include}\", which is neither a header of include/ nor one "
                          "from the repository root: a public header may include only those and the standard library")
    endif()
    list(APPEND rp_queue ${rp_source})
  endforeach()
  string(REGEX REPLACE "^include/raypack/" "" rp_path "${rp_header}")
  file(WRITE "${RP_STAGE_DIR}/raypack/${rp_path}" "${rp_text}")
endwhile()
file(INSTALL "${RP_STAGE_DIR}/raypack" DESTINATION "${CMAKE_INSTALL_PREFIX}/${RP_INCLUDE_DIR}")
cmake_policy(POP)
