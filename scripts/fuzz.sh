#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang-14, ASan + UBSan, ./build-fuzz) and runs each for SECONDS
# (default 600; 0: only build), one after the other, niced, in one process each, on a working copy of its checked-in corpus
# (build-fuzz/corpus/<harness>, which keeps what the run adds). Prints each run's totals; inputs that
# crash land in build-fuzz/crashes/<harness>/, pipeline findings that do not crash (InternalError, lost
# or flipped triangles) in build-fuzz/findings/. See FUZZING.md.
#   scripts/fuzz.sh [SECONDS] [HARNESS...]     e.g. scripts/fuzz.sh 60 fuzz_obj
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
shift || true
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(fuzz_obj fuzz_ply fuzz_gltf fuzz_image fuzz_pipeline)

generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if [ ! -f build-fuzz/CMakeCache.txt ]; then
  cmake -S . -B build-fuzz "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 -DTIGHTEX_FUZZ=ON \
    -DTIGHTEX_BUILD_TESTS=OFF -DTIGHTEX_BUILD_BENCH=OFF >/dev/null
fi
nice -n 10 cmake --build build-fuzz --parallel 2 --target "${harnesses[@]}"
[ "$seconds" -gt 0 ] || exit 0

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export TIGHTEX_FUZZ_FINDINGS=$PWD/build-fuzz/findings
max_len() {
  case $1 in
    fuzz_obj) echo 4096 ;;
    fuzz_ply) echo 4096 ;;
    fuzz_gltf) echo 8192 ;;
    fuzz_image) echo 16384 ;;
    fuzz_pipeline) echo 1024 ;;
  esac
}
status=0
for h in "${harnesses[@]}"; do
  corpus=build-fuzz/corpus/$h
  mkdir -p "$corpus" "build-fuzz/crashes/$h"
  cp -n fuzz/corpus/$h/* "$corpus"/ 2>/dev/null || true
  dict=()
  [ -f fuzz/$h.dict ] && dict=(-dict=fuzz/$h.dict)
  log=build-fuzz/$h.log
  echo "== $h: ${seconds}s, log $log"
  rc=0
  nice -n 10 build-fuzz/fuzz/$h "$corpus" "${dict[@]}" -max_total_time="$seconds" -max_len="$(max_len "$h")" \
    -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="build-fuzz/crashes/$h/" </dev/null >"$log" 2>&1 || rc=$?
  # Totals: the last status line (execs, cov, ft, corpus) and the final stats.
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  execs=$(grep -Eo 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -Eo '[0-9]+$' | tail -1 || true)
  rate=$(grep -Eo 'stat::average_exec_per_sec: *[0-9]+' "$log" | grep -Eo '[0-9]+$' | tail -1 || true)
  crashes=$(find "build-fuzz/crashes/$h" -type f | wc -l)
  findings=$(grep -c '^FINDING' "$log" || true)
  echo "   last: $last"
  echo "   execs ${execs:-?}, exec/s ${rate:-?}, corpus files $(ls "$corpus" | wc -l), crash files $crashes, findings $findings, exit $rc"
  [ "$rc" -eq 0 ] || status=1
done
exit $status
