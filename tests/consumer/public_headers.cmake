# Package.TheInstallRefusesAnInternalHeader: cmake/install_headers.cmake run on a copy of the
# repository's headers, as they are and with one change each that would make an internal
# header public: the copy as it is installs, and each change stops the install with the
# message that names it. Run with cmake -P and -DSOURCE_DIR (the repository), -DGENERATED_DIR
# (the build's made headers), -DWORK (a scratch folder).
cmake_policy(VERSION 3.25)  # scripts start with old policies (IN_LIST)
set(script "${SOURCE_DIR}/cmake/install_headers.cmake")

# Copies the headers into WORK/src, changes `file` there (nothing for ""): replaces `from` by
# `to`, or appends the line `to` when `from` is "", runs the install script into WORK/prefix,
# and fails unless it succeeds (`expected` "") or fails with a message matching `expected`.
function(install_case what file from to expected)
  file(REMOVE_RECURSE "${WORK}")
  foreach(folder include base core io render analysis backends)
    file(COPY "${SOURCE_DIR}/${folder}" DESTINATION "${WORK}/src" FILES_MATCHING PATTERN "*.h")
  endforeach()
  if(file AND from STREQUAL "")
    file(APPEND "${WORK}/src/${file}" "${to}\n")
  elseif(file)
    file(READ "${WORK}/src/${file}" text)
    string(FIND "${text}" "${from}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "${what}: ${file} has no '${from}' to change")
    endif()
    string(REPLACE "${from}" "${to}" text "${text}")
    file(WRITE "${WORK}/src/${file}" "${text}")
  endif()
  execute_process(COMMAND "${CMAKE_COMMAND}" "-DRP_SOURCE_DIR=${WORK}/src" "-DRP_GENERATED_DIR=${GENERATED_DIR}"
                          "-DRP_STAGE_DIR=${WORK}/stage" -DRP_INCLUDE_DIR=include "-DCMAKE_INSTALL_PREFIX=${WORK}/prefix"
                          -P "${script}"
                  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  string(REGEX REPLACE "[ \t\r\n]+" " " err "${err}")  # CMake wraps its messages
  if(expected STREQUAL "" AND NOT status EQUAL 0)
    message(FATAL_ERROR "${what}: the install failed (${status}): ${err}")
  elseif(NOT expected STREQUAL "" AND status EQUAL 0)
    message(FATAL_ERROR "${what}: the install succeeded; it should have stopped with '${expected}'")
  elseif(NOT expected STREQUAL "" AND NOT err MATCHES "${expected}")
    message(FATAL_ERROR "${what}: the install failed without the message '${expected}': ${err}")
  endif()
  message(STATUS "${what}: as expected")
endfunction()

install_case("the headers as they are" "" "" "" "")
file(GLOB_RECURSE installed RELATIVE "${WORK}/prefix/include" "${WORK}/prefix/include/*")
foreach(internal raypack/base/error.h raypack/base/lanes.h raypack/base/pow.h raypack/base/trig.h
        raypack/base/offset.h raypack/render/camera_lanes.h)
  if(internal IN_LIST installed)
    message(FATAL_ERROR "the headers as they are: ${internal} was installed")
  endif()
endforeach()
install_case("a public header includes the lane arithmetic" render/camera.h "" "#include \"base/lanes.h\""
             "render/camera.h includes \"base/lanes.h\", which is not a public header")
install_case("a public header includes the check macros" core/ray.h "" "#include \"base/error.h\""
             "core/ray.h includes \"base/error.h\", which is not a public header")
install_case("a public header defines a check macro" base/math.h "" "#define RP_DCHECK(cond) ((void)0)"
             "base/math.h defines RP_DCHECK: a public header defines no macro but RAYPACK_")
install_case("a public header defines a RAYPACK_ macro" base/math.h "" "#define RAYPACK_EXAMPLE 1" "")
install_case("a listed header is no longer included" include/raypack/raypack.h "#include \"core/thread_limit.h\"" ""
             "core/thread_limit.h is in rp_public_headers .* but raypack.h no longer includes it")
file(REMOVE_RECURSE "${WORK}")
