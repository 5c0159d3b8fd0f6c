#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The README's first command: install what is missing, build the release tree (the `strike` tool
# and libstrike: everything `cmake --install build/release` installs, README "Install"), and
# render an example scene (a steel bar dropped on concrete) to out/bar-drop.wav, with its
# spectrogram.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release
mkdir -p out
strike=build/release/tools/strike
"$strike" render examples/scenes/bar-drop.json -o out/bar-drop.wav --events out/bar-drop-events.csv
"$strike" analyze out/bar-drop.wav --peaks 8 --spectrogram out/bar-drop.png
echo "quickstart: wrote out/bar-drop.wav (sound), out/bar-drop.png (spectrogram), out/bar-drop-events.csv (contacts)"
echo "quickstart: the tool is $strike; to put \`strike\` on your PATH: cmake --install build/release --prefix ~/.local (README, Install)"
