#!/usr/bin/env bash
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
