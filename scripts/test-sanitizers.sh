#!/usr/bin/env bash
# The unit tests built with AddressSanitizer + UndefinedBehaviorSanitizer (CMake preset "asan",
# ./build-asan): every test on generated meshes, the hostile-input catalogue and the fuzz corpus. Of the
# real scans in ../shared/data only fuze (the smallest, and the one JPEG texture) goes through the CLI
# here; the Release suite (scripts/test.sh) runs them all, and the --target-psnr / --max-bytes search
# (probes of the baked atlas, then one more bake: the same code as one run) too. Any report
# fails the run.
# Kept short for CI: the preset builds the library and the CLI at -O1 -g1 without the tools (the tests
# run no slower than at -O2), as unity sources without UBSan's null, vptr and pointer-overflow checks
# (CMakeLists.txt), and the test sources at -Og (tests/CMakeLists.txt); it measures the surface
# PSNR on 100,000 points, not 1,000,000 (src/report/metrics.hpp: the same code, which took over half
# the tests' time; the Release suite measures with 1,000,000); the real scans but fuze are left to the
# Release suite; and the test binary runs as two processes per core (gtest shards, which deal the tests
# round-robin: with two per core a shard that drew the long ones holds up less) instead of one per
# test, which would pay the sanitizer start-up (0.2 s) per test. On the 2-core development VM the tests
# took 182 s as four shards, 206 s as two.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/gltf-checks.sh
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
[ -f build-asan/CMakeCache.txt ] || cmake --preset asan "${generator[@]}" >/dev/null
cmake --build build-asan --parallel "$(nproc)"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
cd build-asan/tests  # the tests' working directory, as under ctest
logs=$(mktemp -d)
shards=$((2 * $(nproc)))
# The one test that takes over half a shard's time under the sanitizers (80 s: two multigrid solves of
# a 230,000-unknown system) runs in a process of its own from the start, so that the shard that drew
# it does not finish a minute after the others (the tests 166 -> 144 s on the development VM).
alone='Multigrid.SweepsInHalvesConvergeAsOneThreadsAndRepeatExactly'
pids=()
for ((i = 0; i < shards; ++i)); do
  GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$i timeout 1800 ./tightex_tests --gtest_filter="-*RealData*:TextureBytes.WebpTargetPsnr*:$alone" >"$logs/shard$i.log" 2>&1 &
  pids+=($!)
done
timeout 900 ./tightex_tests --gtest_filter='Scans/RealData.CliOutputIsOneFoldFreeChartPerComponentFillingTheTexture/fuze' >"$logs/fuze.log" 2>&1 &
pids+=($!)
timeout 900 ./tightex_tests --gtest_filter="$alone" >"$logs/alone.log" 2>&1 &
pids+=($!)
failed=0
for ((i = 0; i < ${#pids[@]}; ++i)); do
  log=$logs/shard$i.log
  ((i == shards)) && log=$logs/fuze.log
  ((i == shards + 1)) && log=$logs/alone.log
  if ! wait "${pids[$i]}"; then
    failed=1
    echo "=== FAILED: $log"
    cat "$log"
  fi
done
for log in "$logs"/*.log; do grep -h '^\[==========\].*ran\|^\[  PASSED  \]\|^\[  SKIPPED \]' "$log" | sed "s|^|$(basename "$log" .log): |"; done
rm -rf "$logs"
exit "$failed"
