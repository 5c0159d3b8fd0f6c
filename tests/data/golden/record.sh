#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Re-records the golden renders that tests/unit/cli/golden_test.cpp compares against.
# Run it ONLY when a change is meant to change what Strike sounds like, and say in the commit
# what changed and why (README.md beside this file). Usage: bash tests/data/golden/record.sh [STRIKE]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
strike="${1:-$root/build/ci/tools/strike}"
cache="$(mktemp -d)"
trap 'rm -rf "$cache"' EXIT
# The scalar kernel: the plainest arithmetic (the others agree within -120 dB, tested).
"$strike" render "$root/examples/scenes/bar-drop.json" -o "$here/bar-drop.wav" --duration 1.5 \
  --cache "$cache" --quiet --simd scalar
"$strike" hit "$cache"/*.modes -o "$here/bar-hit.wav" --vertex 12 --impulse 0,0.004,-0.01 --duration 1 \
  --quiet --simd scalar
echo "recorded $here/bar-drop.wav and $here/bar-hit.wav"
