#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# tools/test.sh's runtime-only stage hides every package the project looks for: each name in a
# find_package() of any CMakeLists.txt must be in the stage's CMAKE_DISABLE_FIND_PACKAGE_ list,
# so a new dependency cannot slip into the runtime build unnoticed, and the stage must run.
# Usage: runtime_stage_test.sh SOURCE_DIR
set -u
src=$1
test_sh=$src/tools/test.sh
fail() { echo "FAIL: $*"; exit 1; }

hidden=$(sed -n 's/^ *for package in \(.*\); do$/\1/p' "$test_sh")
[ -n "$hidden" ] || fail "tools/test.sh has no 'for package in ...; do' list of hidden packages"
grep -q '^stage "runtime-only build + tests" runtime_only_build_and_tests$' "$test_sh" ||
  fail "tools/test.sh does not run the runtime-only stage"

used=$(find "$src" -name CMakeLists.txt -not -path "$src/build/*" -exec grep -ho 'find_package([A-Za-z0-9_]*' {} + |
       sed 's/find_package(//' | sort -u)
[ -n "$used" ] || fail "found no find_package() in the project's CMakeLists.txt files"
for package in $used; do
  grep -qw -- "$package" <<<"$hidden" || fail "find_package($package) is not hidden in tools/test.sh's runtime-only stage"
done
echo "runtime-only stage hides every find_package: $(echo $used)"
