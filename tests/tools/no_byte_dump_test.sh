#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# No test compares whole files with EXPECT_EQ/ASSERT_EQ/EXPECT_NE: on a mismatch gtest prints both
# files as escaped bytes (a failing WAV comparison once wrote 7 MB of log). Use
# test::sameBytes / test::sameValues (tests/unit/common/same_bytes.hpp), which print a summary.
# Usage: no_byte_dump_test.sh SOURCE_DIR
set -u
pattern='(EXPECT|ASSERT)_(EQ|NE)\([^;<]*(slurp|readBytes|encodeBank)\('
if found=$(grep -rnE "$pattern" "$1/tests" --include='*.cpp' --include='*.hpp'); then
  echo "FAIL: whole-file comparisons that would dump the files on failure; use test::sameBytes:"
  echo "$found"
  exit 1
fi
echo "no EXPECT_EQ on file contents in tests/"
