# Package.PkgConfigBuildsTheSameConsumer (project/trace_both.cpp) and
# Package.VersionsAndThreadLimitsHoldWithPkgConfig (api/api_checks.cpp): compiles SOURCE/NAME.cpp
# with the flags of `pkg-config --cflags --libs raypack` (PKG_CONFIG_PATH at the install in
# PREFIX) and runs it (run_consumer.cmake). Run with cmake -P and -DPREFIX, -DLIBDIR, -DSOURCE,
# -DNAME, -DBINARY, -DCXX, -DCXX_FLAGS, -DLINKER_FLAGS.
file(REMOVE_RECURSE "${BINARY}")
file(MAKE_DIRECTORY "${BINARY}")
set(pkg_config "${CMAKE_COMMAND}" -E env "PKG_CONFIG_PATH=${PREFIX}/${LIBDIR}/pkgconfig" pkg-config)
execute_process(COMMAND ${pkg_config} --cflags --libs raypack OUTPUT_VARIABLE flags RESULT_VARIABLE status
                OUTPUT_STRIP_TRAILING_WHITESPACE)
execute_process(COMMAND ${pkg_config} --modversion raypack OUTPUT_VARIABLE version OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT status EQUAL 0 OR NOT flags MATCHES "-lraypack")
  message(FATAL_ERROR "pkg-config does not know raypack in ${PREFIX}/${LIBDIR}/pkgconfig (${status}): ${flags}")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
separate_arguments(cxx_flags UNIX_COMMAND "${CXX_FLAGS} ${LINKER_FLAGS}")
set(PROGRAM "${BINARY}/${NAME}")
execute_process(COMMAND "${CXX}" -std=c++20 -O2 ${cxx_flags} "-DRAYPACK_FOUND_VERSION=\"${version}\""
                        "${SOURCE}/${NAME}.cpp" ${flags} -o "${PROGRAM}" RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "compiling ${NAME}.cpp with pkg-config's flags failed (${status})")
endif()
set(ENVIRONMENT "LD_LIBRARY_PATH=${PREFIX}/${LIBDIR}")
include("${CMAKE_CURRENT_LIST_DIR}/run_consumer.cmake")
