#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The README's first command: install what is missing, build the release tool, and make a sound.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target strike_cli
mkdir -p out
strike=build/release/tools/strike
"$strike" modes box:0.3,0.02,0.02 --material steel --order 2 -o out/steel-bar.modes
"$strike" hit out/steel-bar.modes -o out/steel-bar-hit.wav --duration 3
"$strike" analyze out/steel-bar-hit.wav --peaks 8
echo "quickstart: wrote out/steel-bar-hit.wav"
