#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The test command: installs the Debian packages, builds in Release, runs the default test suite
# (everything but the `sweep` label) and checks the installed CMake package with examples/minimal.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
BUILD=${BUILD:-build}
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$BUILD" -j"$(nproc)"
ctest --test-dir "$BUILD" -LE sweep --output-on-failure -j"$(nproc)"
if [ -f scripts/test-install.sh ]; then bash scripts/test-install.sh "$BUILD"; fi
# The Python module, when built: installed for the system's python3 (under /usr/local), so that
# `python3 -c "import envpis"` works after this script.
if grep -q '^ENVPIS_BUILD_PYTHON:BOOL=ON' "$BUILD/CMakeCache.txt"; then
  cmake --install "$BUILD" --component python --prefix /usr/local >/dev/null
  PY=$(sed -n 's/^Python3_EXECUTABLE:FILEPATH=//p' "$BUILD/CMakeCache.txt")
  (cd / && "$PY" -c "import envpis; print('test: python module', envpis.__file__)")
fi
