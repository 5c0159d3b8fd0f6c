#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the libFuzzer targets (clang, ASan + UBSan) and runs each for SECONDS over its seed
# corpus (tests/fuzz/corpus/<target without fuzz_>/, read only; new inputs go to build-fuzz/corpus/<target>/).
# Findings are written to build-fuzz/findings/<target>/; the script exits 1 if any target failed.
#   usage: tools/fuzz.sh [SECONDS (default 60)] [TARGET...]    e.g. tools/fuzz.sh 10   (CI smoke)
#   STRIKE_FUZZ_JOBS=N runs N targets at a time (default 1).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
all=(fuzz_obj fuzz_stl fuzz_ply fuzz_gmsh fuzz_tetgen fuzz_scene fuzz_bank fuzz_capi_bank)
targets=("${@:-${all[@]}}")
[ $# -eq 0 ] && targets=("${all[@]}")
build="${STRIKE_FUZZ_BUILD_DIR:-build-fuzz}"
if [ ! -f "$build/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSTRIKE_BUILD_FUZZERS=ON \
    -DSTRIKE_BUILD_TESTS=OFF -DSTRIKE_BUILD_TOOLS=OFF -DSTRIKE_BUILD_EXAMPLES=OFF -DSTRIKE_INSTALL=OFF >/dev/null
fi
cmake --build "$build" --target "${targets[@]}"
# STRIKE_FUZZ_JOBS targets run at a time (default 1), each a single process on one core for SECONDS:
# the same fuzzing per target, in 1/JOBS of the wall time (tools/test.sh runs 2 on CI's 2 cores).
jobs="${STRIKE_FUZZ_JOBS:-1}"
run_target() {
  local t=$1
  mkdir -p "$build/corpus/$t" "$build/findings/$t"
  # -rss_limit_mb and -timeout: a slow or greedy input is a finding, like a crash.
  if "$build/tests/fuzz/$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
       -print_final_stats=1 -artifact_prefix="$build/findings/$t/" "$build/corpus/$t" "tests/fuzz/corpus/${t#fuzz_}" \
       >"$build/findings/$t/log.txt" 2>&1; then
    echo ok >"$build/findings/$t/status"
  else
    echo FAILED >"$build/findings/$t/status"
  fi
}
running=0
for t in "${targets[@]}"; do
  rm -f "$build/findings/$t/status"
  run_target "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
done
wait
failed=0
for t in "${targets[@]}"; do
  log="$build/findings/$t/log.txt"
  status=$(cat "$build/findings/$t/status" 2>/dev/null || echo FAILED)
  [ "$status" = ok ] || failed=1
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  printf '%-16s %-6s %8s s  %10s execs  %7s exec/s  cov %6s  ft %6s\n' "$t" "$status" "$seconds" "$execs" \
    "$(( execs / (seconds > 0 ? seconds : 1) ))" "$cov" "$ft"
  [ "$status" = ok ] || tail -30 "$log"
done
exit $failed
