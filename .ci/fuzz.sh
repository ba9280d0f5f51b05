#!/usr/bin/env bash
# Fuzzes raypack's file readers with libFuzzer under AddressSanitizer and UBSan: installs clang
# and its runtime libraries when missing (as .ci/setup.sh does), builds the five targets of
# tests/fuzz/ in ./build-fuzz (clang, RAYPACK_FUZZ=ON, RelWithDebInfo with line tables only
# (-g1, as .ci/sanitize.sh), sanitizers on every
# file so the readers in rp_io are checked too), then runs each for a bounded time on a
# copy of its seed corpus (tests/fuzz/corpus/<target>/ plus tests/fuzz/regression/<target>/),
# so the repository is never modified.
#
# Any finding (crash, sanitizer report, an exception other than rp::Error, a timeout of 10 s,
# more than 2 GB of memory) fails the script after naming the input libFuzzer saved under
# build-fuzz/artifacts/<target>/. To keep one: minimise it
#   build-fuzz/tests/fuzz/<target> -minimize_crash=1 -runs=100000 <artifact>
# and add it to tests/fuzz/regression/<target>/ (rp_test_fuzz_corpus then replays it).
#
# Usage: .ci/fuzz.sh    (from anywhere; environment: RAYPACK_FUZZ_SECONDS per target, default
#                        20; RAYPACK_JOBS build jobs, default 2)
set -euo pipefail
cd "$(dirname "$0")/.."

.ci/apt-install.sh fuzz clang libclang-rt-14-dev

jobs=${RAYPACK_JOBS:-2}
seconds=${RAYPACK_FUZZ_SECONDS:-20}
build=build-fuzz
targets=(fuzz_obj fuzz_ply fuzz_json fuzz_rayfile fuzz_gltf)
declare -A dictionary=([fuzz_obj]=obj.dict [fuzz_ply]=ply.dict [fuzz_json]=json.dict [fuzz_rayfile]=rayfile.dict
                       [fuzz_gltf]=gltf.dict)

# -fno-sanitize-recover: a UBSan report stops the run like an ASan one, so libFuzzer keeps the
# input. _GLIBCXX_ASSERTIONS: operator[] past size() inside a vector's capacity is caught too.
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DRAYPACK_FUZZ=ON \
  -DRAYPACK_BUILD_BENCH=OFF -DRAYPACK_BUILD_PYTHON=OFF -DCMAKE_CXX_FLAGS="$sanitize -D_GLIBCXX_ASSERTIONS" \
  -DCMAKE_EXE_LINKER_FLAGS="$sanitize" -DCMAKE_SHARED_LINKER_FLAGS="$sanitize" >/dev/null
cmake --build "$build" -j"$jobs" --target rp_fuzz_targets

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t artifacts=$build/artifacts/$t log=$build/logs/$t.log
  rm -rf "$corpus" "$artifacts"
  mkdir -p "$corpus" "$artifacts" "$(dirname "$log")"
  cp tests/fuzz/corpus/"$t"/* "$corpus"/
  if [ -d tests/fuzz/regression/"$t" ]; then cp tests/fuzz/regression/"$t"/* "$corpus"/; fi
  echo "fuzz: $t for ${seconds}s (log: $log)"
  rc=0
  "$build"/tests/fuzz/"$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    -dict=tests/fuzz/"${dictionary[$t]}" -artifact_prefix="$artifacts"/ -print_final_stats=1 \
    "$corpus" >"$log" 2>&1 || rc=$?
  # The last status line, e.g. "#123456 DONE cov: 1234 ft: 5678 corp: 90/12Kb exec/s: 2743 ...".
  grep -E '^#[0-9]+' "$log" | tail -n 1 | sed "s/^/fuzz: $t: /" || true
  found=("$artifacts"/*)
  if [ "$rc" -ne 0 ] || [ -e "${found[0]}" ]; then
    status=1
    echo "fuzz: $t FAILED (exit status $rc); the end of its log:" >&2
    tail -n 60 "$log" >&2
    for f in "${found[@]}"; do [ -e "$f" ] && echo "fuzz: $t: artifact: $f" >&2; done
  fi
done
if [ "$status" -ne 0 ]; then
  echo "fuzz: FAILED; reproduce with build-fuzz/tests/fuzz/<target> <artifact>" >&2
else
  echo "fuzz: ${targets[*]}: no findings in ${seconds}s each"
fi
exit "$status"
