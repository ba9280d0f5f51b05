#!/usr/bin/env bash
# Runs the whole test suite under AddressSanitizer (with LeakSanitizer) and UBSan: configures
# ./build-asan (the default compiler, RelWithDebInfo with line tables only (-g1: what a
# sanitizer's report needs, file and line of every frame), every file built with the sanitizers),
# builds what ctest runs and nothing else (rp_tests: every GoogleTest binary of tests/, the
# raypack CLI, libraypack.so and the Python module; not the benchmark rp_bench) in one build
# invocation, and runs ctest (all but the pip install test, below). Any sanitizer report aborts
# its test, so ctest fails.
# The Python tests load the instrumented module into Debian's python3 with the sanitizer's
# runtime preloaded (tests/python/CMakeLists.txt).
# Usage: .ci/sanitize.sh    (from anywhere; RAYPACK_JOBS build jobs, default 2)
set -euo pipefail
cd "$(dirname "$0")/.."

jobs=${RAYPACK_JOBS:-2}
build=build-asan
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
  -DRAYPACK_MPI=ON -DCMAKE_CXX_FLAGS="$sanitize" \
  -DCMAKE_EXE_LINKER_FLAGS="$sanitize" -DCMAKE_SHARED_LINKER_FLAGS="$sanitize" \
  -DCMAKE_MODULE_LINKER_FLAGS="$sanitize" -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null

# The options apply to the test discovery that runs each binary after it is linked, too.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

echo "sanitize: building rp_tests in $build"
cmake --build "$build" -j"$jobs" --target rp_tests

# gtest_discover_tests registers "<binary>_NOT_BUILT" for a test binary that was not built:
# every test ctest knows must have its binary.
if not_built=$(ctest --test-dir "$build" -N | grep -o '[A-Za-z0-9_]*_NOT_BUILT'); then
  echo "sanitize: ctest has tests whose binaries were not built: $not_built" >&2
  exit 1
fi
# Every test but those labelled pip (Python.PipInstallsTheSourceTree): pip builds the package
# anew in a tree of its own, without the sanitizers, so it would check nothing more here and
# compile the module's sources again.
ctest --test-dir "$build" --output-on-failure -j2 -LE '^pip$'
