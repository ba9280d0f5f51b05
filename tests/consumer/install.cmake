# Package.InstallsIntoTheBuildTree: a fresh `cmake --install BUILD_DIR --prefix PREFIX`, then
# the files the README's install tree lists and the version macros of the installed
# raypack/version.h. Run with cmake -P and -DBUILD_DIR, -DPREFIX, -DBINDIR, -DLIBDIR,
# -DINCLUDEDIR, -DVERSION (the project's version).
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}" RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${status})")
endif()
foreach(file ${BINDIR}/raypack ${LIBDIR}/libraypack.so ${INCLUDEDIR}/raypack/raypack.h ${INCLUDEDIR}/raypack/version.h
        ${INCLUDEDIR}/raypack/core/scene.h ${INCLUDEDIR}/raypack/backends/registry.h
        ${LIBDIR}/cmake/raypack/raypackConfig.cmake ${LIBDIR}/cmake/raypack/raypackConfigVersion.cmake
        ${LIBDIR}/cmake/raypack/raypackTargets.cmake ${LIBDIR}/pkgconfig/raypack.pc)
  if(NOT EXISTS "${PREFIX}/${file}")
    message(FATAL_ERROR "the install has no ${file}")
  endif()
endforeach()
# The version macros say the project's version, made by the build from version.h.in.
file(STRINGS "${PREFIX}/${INCLUDEDIR}/raypack/version.h" defines REGEX "^#define RAYPACK_VERSION_")
string(REPLACE "." ";" parts "${VERSION}")
list(GET parts 0 major)
list(GET parts 1 minor)
list(GET parts 2 patch)
foreach(define "#define RAYPACK_VERSION_MAJOR ${major}" "#define RAYPACK_VERSION_MINOR ${minor}"
        "#define RAYPACK_VERSION_PATCH ${patch}" "#define RAYPACK_VERSION_STRING \"${VERSION}\"")
  list(FIND defines "${define}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the installed raypack/version.h has no '${define}' (project version ${VERSION}): ${defines}")
  endif()
endforeach()
# Only the public headers: nothing of the backends' internals or of the SIMD vocabulary, not
# the lane arithmetic of the kernels and the camera (base/lanes.h and what it includes), and no
# header that defines or uses the library's own checks (base/error.h's RP_CHECK and RP_DCHECK,
# whose debug-only one would follow the consumer's NDEBUG).
file(GLOB_RECURSE headers RELATIVE "${PREFIX}/${INCLUDEDIR}" "${PREFIX}/${INCLUDEDIR}/*")
foreach(header IN LISTS headers)
  if(header MATCHES "^raypack/(simd|backends/simd|backends/embree|cli|mpi)/"
     OR header MATCHES "^raypack/(base/(error|lanes|pow|trig|offset)|render/camera_lanes)[.]h$")
    message(FATAL_ERROR "a private header was installed: ${header}")
  endif()
  file(STRINGS "${PREFIX}/${INCLUDEDIR}/${header}" checks REGEX "RP_D?CHECK")
  if(checks)
    message(FATAL_ERROR "the installed ${header} names the library's checks: ${checks}")
  endif()
endforeach()
list(LENGTH headers count)
message(STATUS "installed into ${PREFIX}: ${count} headers")
