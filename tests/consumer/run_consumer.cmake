# Runs a built consumer program (PROGRAM, named NAME: trace_both or api_checks) twice, on its
# scene from arrays and on the embedded default scene; fails when it fails, says "NAME:
# skipped: ..." when it exits 77 (a backend it needs does not run on this CPU). Included by
# cmake_consumer.cmake and pkg_config_consumer.cmake; ENVIRONMENT is a list of NAME=VALUE for
# `cmake -E env`.
foreach(scene IN ITEMS "" default)
  execute_process(COMMAND "${CMAKE_COMMAND}" -E env ${ENVIRONMENT} "${PROGRAM}" ${scene} RESULT_VARIABLE status
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${PROGRAM} ${scene}:\n${out}${err}")
  if(status EQUAL 77)
    message("${NAME}: skipped: ${err}")
    return()
  elseif(NOT status EQUAL 0)
    message(FATAL_ERROR "${PROGRAM} ${scene} failed (${status})")
  endif()
endforeach()
