#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Is the transfer's error estimate honest? For the mug, the glass, the bowl (assets/meshes) and the
# bench plate (box:0.32,0.256,0.004 aluminium, Tet4, 100 modes): each bank's heard modes (every
# N-th, to keep it to minutes) are solved at the default settings and again with a budget of
# REFERENCE unknowns (default 3000) and a tenth of the target (0.5%), and each mode's true error
# (rms over directions, against the reference) is printed beside its estimate, with how many lie
# within it and how many over 3x it (docs/acoustic-transfer.md, "Is the estimate honest?").
# A measurement, not a test: minutes of processor time per object.
#
#   tests/bench/transfer/estimate-honesty.sh BUILD_DIR [OUT_DIR]
#   (BUILD_DIR holds tools/strike and tests/unit/transfer/strike_transfer_tests; REFERENCE=N to change
#   the reference's budget; OBJECTS="bowl plate" for some of them)
set -euo pipefail
build=${1:?usage: estimate-honesty.sh BUILD_DIR [OUT_DIR]}
out=${2:-$(mktemp -d)}
source_dir=$(cd "$(dirname "$0")/../../.." && pwd)
strike=$build/tools/strike
solver=$build/tests/unit/transfer/strike_transfer_tests
reference=${REFERENCE:-3000}
mkdir -p "$out"

declare -A mesh=([mug]=$source_dir/assets/meshes/mug.obj [glass]=$source_dir/assets/meshes/glass.obj
                 [bowl]=$source_dir/assets/meshes/bowl.obj [plate]=box:0.32,0.256,0.004)
declare -A material=([mug]=porcelain [glass]=glass [bowl]=ceramic [plate]=aluminium)
declare -A options=([mug]="--order 2 --max-modes 40" [glass]="--order 2 --max-modes 40"
                    [bowl]="--order 2 --max-modes 40" [plate]="--order 1 --max-modes 100")
declare -A every=([mug]=3 [glass]=3 [bowl]=3 [plate]=10)

for object in ${OBJECTS:-mug glass bowl plate}; do
  bank=$out/$object.modes
  # The modes only (the default max-freq, 20 kHz: every mode is heard at 48 kHz).
  [ -f "$bank" ] || "$strike" modes "${mesh[$object]}" --material "${material[$object]}" ${options[$object]} \
    --no-transfer --no-error-estimate --quiet -o "$bank"
  echo "=== $object (1 mode in ${every[$object]}, reference $reference unknowns at a tenth of the target)"
  STRIKE_TRANSFER_BANK=$bank STRIKE_TRANSFER_EVERY=${every[$object]} STRIKE_TRANSFER_REFERENCE_ELEMENTS=$reference \
    "$solver" --gtest_also_run_disabled_tests --gtest_filter='TransferSolver.DISABLED_PrintsTheSolveOfABankFromTheEnvironment' |
    grep -v '^\[\|^Running main\|^Note:'
done
