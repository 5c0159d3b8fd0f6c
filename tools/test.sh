#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The README's second command (and CI's): install what is missing, build libstrike alone with
# nothing but a compiler and CMake (heavy packages hidden), build everything with warnings as errors,
# fuzz smoke, the test suite under ASan + UBSan and the C API's threading tests under TSan, then
# the whole test suite. Any finding of a fuzzer or sanitizer fails the script (set -e); the table
# of stage times is printed at the end either way (tools/stages.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/stages.sh

ci_build() {
  cmake --preset ci >/dev/null
  cmake --build --preset ci
}
asan_build() {
  cmake --preset asan >/dev/null
  cmake --build --preset asan
}
# libstrike alone (STRIKE_RUNTIME_ONLY) with every package the project looks for hidden from CMake:
# each find_package disabled (tests/tools checks that none is missing from this list), pkg-config
# pointed at nothing, and find_library/find_path blind to the system prefixes. It configures only
# if the runtime build asks for none of them; a full configure under the same hiding must fail,
# or the hiding proves nothing. Build dir build/runtime (seconds: the runtime only).
runtime_only_build_and_tests() {
  local hide=(--no-warn-unused-cli -DCMAKE_IGNORE_PREFIX_PATH="/usr;/usr/local")
  for package in Eigen3 PkgConfig Bullet nlohmann_json GTest Threads Python pybind11 benchmark; do
    hide+=("-DCMAKE_DISABLE_FIND_PACKAGE_${package}=ON")
  done
  if PKG_CONFIG_LIBDIR= cmake -S . -B build/runtime-hiding-check -G Ninja "${hide[@]}" >/dev/null 2>&1; then
    echo "runtime-only stage: the full build configured with the packages hidden; the hiding does not work" >&2
    return 1
  fi
  PKG_CONFIG_LIBDIR= cmake -S . -B build/runtime -G Ninja -DCMAKE_BUILD_TYPE=Release -DSTRIKE_RUNTIME_ONLY=ON \
    -DSTRIKE_WERROR=ON "${hide[@]}" >/dev/null
  cmake --build build/runtime
  ctest --test-dir build/runtime -j2 --output-on-failure
}
tsan_build_and_tests() {
  cmake --preset tsan >/dev/null
  cmake --build --preset tsan
  ctest --preset tsan -j2
}

stage "install dependencies" bash tools/install-deps.sh
stage "runtime-only build + tests" runtime_only_build_and_tests
stage "ci build (-Werror)" ci_build
# Fuzz smoke: every parser's libFuzzer target, built with clang + ASan + UBSan (build-fuzz/;
# the parsers and what they link only, no solver: tools.scene_file_parser_links_no_solver), runs 10 s
# over its seed corpus, two targets at a time (one process each: CI's 2 cores);
# a crash, leak, UB, >10 s input or >2 GB RSS fails CI. STRIKE_FUZZ_SMOKE=0 skips it.
if [ "${STRIKE_FUZZ_SMOKE:-1}" = 1 ]; then
  stage "fuzz smoke" env STRIKE_FUZZ_JOBS="${STRIKE_FUZZ_JOBS:-2}" bash tools/fuzz.sh "${STRIKE_FUZZ_SECONDS:-10}"
fi
# Sanitizers. STRIKE_SANITIZERS=0 skips both.
#  asan: the CLI and every test program at -O1 -g with assertions, ASan + UBSan; UB aborts
#        (-fno-sanitize-recover), leaks fail (detect_leaks=1): options in CMakePresets.json.
#        Its test preset leaves out a few tests (filter.exclude) that are slow under ASan only
#        because they repeat heavy numerical work (BEM transfer solves, eigen-solves, long
#        renders) whose code runs under ASan in lighter tests; the ci suite below runs them all:
#          CliAccuracy.BenchAccuracyWritesItsTables: the accuracy study; its solvers and tables'
#            code run in the other CliAccuracy and ErrorEstimate tests.
#          EveryExample/ViaLibrary for ball_rolls_across_plate, block_slides_down_plank,
#            glass_on_table, marbles_in_bowl: each is mostly the BEM solve of a large plate,
#            plank, table or bowl (ball_rolls: 2.4 min under ASan) before two renders;
#            --via-library (the C API step by step, with rolling, sliding and resting contacts)
#            runs under ASan for bar_drop, blocks_falling, coin_spin and spoon_scrapes_plate.
#          TransferSolver.SphereWithYnmAccelerationGivesTheExactExteriorSolution,
#            TransferSolver.TheToleranceConvergesAtTheOrderOfConstantElements,
#            SphereDirectivity.*: fine BEM solves of a sphere against closed forms; the solver
#            runs under ASan in the other TransferSolver and TransferRender tests.
#          TransferRender.TheBarSolvedToThreeCutOffsSoundsTheSame: three transfer solves of one
#            bar; one-cut-off renders of bars with their transfer run in TransferRender, Golden
#            and BarDrop.
#          RollingSound.TheMarblesInTheBowlAudiblyRoll: the bowl's solve; rolling runs under
#            ASan in RollingSound's sphere-on-plate and spoon tests.
#          DocsCommands.EveryCommandInTheReadmeAndDocsRuns: the docs' commands, mostly the
#            bowl's eigen-solve (twice) and the bar's; each command's code runs under ASan in
#            the Cli*, Newcomer* and FirstHour* tests.
#  tsan: the C API's threading tests only (producers, render thread, stress).
if [ "${STRIKE_SANITIZERS:-1}" = 1 ]; then
  stage "asan + ubsan build" asan_build
  stage "asan + ubsan tests" ctest --preset asan -j2
  stage "tsan build + tests" tsan_build_and_tests
fi
# The Python package (python/tests) against the ci build's module and CLI, with Debian's python3
# (python3-numpy, python3-distributed). Exit 5 (no tests collected) fails too.
stage "python tests" env PYTHONPATH=build/ci/python /usr/bin/python3 -m pytest -q -p no:cacheprovider python/tests
# The test suite last; its summary is followed by the stage table.
stage "test suite (ci)" ctest --preset ci -j2
