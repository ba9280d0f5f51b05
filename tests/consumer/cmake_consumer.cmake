# Package.AConsumerProjectTracesBothBackends (project/) and
# Package.VersionsAndThreadLimitsHoldInACMakeConsumer (api/): configures the project in
# SOURCE in BINARY with PREFIX as its CMAKE_PREFIX_PATH (as a user would), checks that
# find_package found the package installed there, builds it and runs its program NAME
# (run_consumer.cmake). Run with cmake -P and -DPREFIX, -DSOURCE, -DNAME, -DBINARY, -DCXX,
# -DCXX_FLAGS, -DLINKER_FLAGS, -DBUILD_TYPE.
file(REMOVE_RECURSE "${BINARY}")
execute_process(COMMAND "${CMAKE_COMMAND}" -S "${SOURCE}" -B "${BINARY}" "-DCMAKE_PREFIX_PATH=${PREFIX}"
                        "-DCMAKE_CXX_COMPILER=${CXX}" "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}"
                        "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}" "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}"
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "configuring the consumer project failed (${status})")
endif()
file(STRINGS "${BINARY}/CMakeCache.txt" found REGEX "^raypack_DIR:")
if(NOT found MATCHES "=${PREFIX}/")
  message(FATAL_ERROR "find_package(raypack) found ${found}, not the package installed in ${PREFIX}")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" --build "${BINARY}" RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "building the consumer project failed (${status})")
endif()
set(PROGRAM "${BINARY}/${NAME}")
set(ENVIRONMENT "")
include("${CMAKE_CURRENT_LIST_DIR}/run_consumer.cmake")
