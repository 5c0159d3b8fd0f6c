#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs the `strike` Python package (docs/install.md) for Debian's python3, from this clone, with
# Debian packages only (tools/install-deps.sh: python3-dev, pybind11-dev, python3-numpy,
# python3-distributed): builds build/release and installs into PREFIX (default ~/.local), i.e.
# PREFIX/lib/python3.11/site-packages/strike, which /usr/bin/python3 searches for ~/.local, and
# PREFIX/bin/strike-batch. Usage: bash tools/install-python.sh [PREFIX]
set -euo pipefail
cd "$(dirname "$0")/.."
prefix="${1:-$HOME/.local}"
bash tools/install-deps.sh
cmake --preset release -DSTRIKE_BUILD_PYTHON=ON >/dev/null
cmake --build --preset release --target strike_python strike_cli
cmake --install build/release --component python --prefix "$prefix"
site="$prefix/$(grep '^STRIKE_PYTHON_INSTALL_DIR:' build/release/CMakeCache.txt | cut -d= -f2)"
if /usr/bin/python3 -c "import strike" 2>/dev/null; then
  /usr/bin/python3 -c "import strike; print('install-python: strike', strike.__version__, 'in', strike.__path__[0])"
else
  echo "install-python: installed in $site; add it to PYTHONPATH: export PYTHONPATH=$site"
fi
