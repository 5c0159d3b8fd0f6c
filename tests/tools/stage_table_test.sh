#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# tools/stages.sh (tools/test.sh's stage timing): when a stage fails, the table of stage times is
# still printed, the failed stage is marked with its exit code, later stages do not run, and the
# script's exit code is the failure's. Usage: stage_table_test.sh SOURCE_DIR
set -u
stages=$1/tools/stages.sh
fail() { echo "FAIL: $*"; echo "--- output:"; echo "$out"; exit 1; }

out=$(bash -c 'set -euo pipefail; source "$1"; stage "first passes" true; stage "second fails" bash -c "exit 3"; stage "never runs" true' _ "$stages" 2>&1)
rc=$?
[ "$rc" = 3 ] || fail "exit code $rc, expected 3 (the failed stage's)"
grep -q '^Time per stage:$' <<<"$out" || fail "no stage table after a failed stage"
grep -Eq '^first passes +[0-9]+ s$' <<<"$out" || fail "the passed stage is not in the table"
grep -Eq '^second fails +[0-9]+ s  FAILED \(exit 3\)$' <<<"$out" || fail "the failed stage is not marked FAILED (exit 3)"
grep -q 'never runs' <<<"$out" && fail "a stage after the failure ran"

out=$(bash -c 'set -euo pipefail; source "$1"; stage "one" true; stage "two" true' _ "$stages" 2>&1)
rc=$?
[ "$rc" = 0 ] || fail "exit code $rc after passing stages"
grep -Eq '^two +[0-9]+ s$' <<<"$out" || fail "no table after passing stages"
grep -q FAILED <<<"$out" && fail "FAILED printed though every stage passed"

# tools/test.sh itself uses the stage machinery (a bare command would escape the table).
grep -q '^source tools/stages.sh$' "$1/tools/test.sh" || fail "tools/test.sh does not source tools/stages.sh"
echo "stage table: printed on failure (exit code kept) and on success"
