#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs the Debian 12 packages Strike builds with, if any is missing. Idempotent.
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config
  libeigen3-dev          # FEM, dense/sparse linear algebra (MPL2)
  libsuitesparse-dev     # CHOLMOD supernodal Cholesky (LGPL)
  libopenblas-dev        # BLAS under CHOLMOD
  libarpack2-dev         # shift-invert Lanczos (BSD)
  libtet1.5-dev          # TetGen tetrahedralization (AGPL: command-line tool only)
  libbullet-dev          # rigid-body simulation, double-precision libraries (zlib)
  libsndfile1-dev        # WAV/FLAC (LGPL)
  libfftw3-dev           # FFT analysis (GPL: tool and tests only)
  libmysofa-dev          # SOFA head-related responses for binaural output (BSD: tools only; its libmysofa1 ships the MIT KEMAR set)
  nlohmann-json3-dev     # JSON (MIT)
  libgtest-dev           # tests
  lv2-dev                # examples/lv2 plugin headers (ISC)
  liblilv-dev lilv-utils # examples/lv2 host test, lv2ls/lv2info (ISC)
  clang libclang-rt-14-dev # libFuzzer + ASan/UBSan for the fuzz smoke run (tools/fuzz.sh)
  python3-dev pybind11-dev # the strike Python package (python/)
  python3-numpy python3-pytest # its arrays and tests
  python3-venv python3-pip python3-setuptools python3-wheel # pip install ./python into a venv, offline
  python3-distributed    # strike batch: Dask local or remote clusters (BSD)
  python3-matplotlib     # examples/python spectrogram plots
)
[ "${STRIKE_BENCHMARKS:-0}" = 1 ] && packages+=(libbenchmark-dev)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
