#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The README's second command (and CI's): install what is missing, build with warnings as errors,
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
tsan_build_and_tests() {
  cmake --preset tsan >/dev/null
  cmake --build --preset tsan
  ctest --preset tsan -j2
}

stage "install dependencies" bash tools/install-deps.sh
stage "ci build (-Werror)" ci_build
# Fuzz smoke (issue 7): every parser's libFuzzer target, built with clang + ASan + UBSan (build-fuzz/),
# runs 10 s over its seed corpus; a crash, leak, UB, >10 s input or >2 GB RSS fails CI.
# STRIKE_FUZZ_SMOKE=0 skips it.
if [ "${STRIKE_FUZZ_SMOKE:-1}" = 1 ]; then
  stage "fuzz smoke" bash tools/fuzz.sh "${STRIKE_FUZZ_SECONDS:-10}"
fi
# Sanitizers (issue 7). STRIKE_SANITIZERS=0 skips both.
#  asan: the CLI and every test program at -O1 -g with assertions, ASan + UBSan; UB aborts
#        (-fno-sanitize-recover), leaks fail (detect_leaks=1): options in CMakePresets.json.
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
