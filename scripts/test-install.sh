#!/usr/bin/env bash
# Checks the installed CMake package the way an outside project sees it: installs BUILD_DIR into a
# temporary prefix, configures examples/minimal against it (find_package(envpis CONFIG REQUIRED)),
# builds it and runs it. Fails on any error. Usage: scripts/test-install.sh BUILD_DIR
set -euo pipefail
if [ $# -ne 1 ]; then
  echo "usage: $0 BUILD_DIR" >&2
  exit 2
fi
BUILD=$(cd "$1" && pwd)  # relative to the caller's directory
cd "$(dirname "$0")/.."
SRC=$(pwd)
TMP=$(mktemp -d "${TMPDIR:-/tmp}/envpis-test-install.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
PREFIX="$TMP/prefix"

echo "== install $BUILD into $PREFIX"
cmake --install "$BUILD" --prefix "$PREFIX" >"$TMP/install.log" || { cat "$TMP/install.log"; exit 1; }
find "$PREFIX" -name envpisConfig.cmake | grep -q . \
  || { echo "test-install: envpisConfig.cmake was not installed" >&2; exit 1; }

echo "== configure and build examples/minimal against the installed package"
GEN=()
if command -v ninja >/dev/null; then GEN=(-G Ninja); fi
cmake -S "$SRC/examples/minimal" -B "$TMP/build" "${GEN[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON
cmake --build "$TMP/build"

echo "== run"
"$TMP/build/envpis_minimal"

# The Python module, when the build has it: installed under the prefix and importable from there.
PY=$(sed -n 's/^Python3_EXECUTABLE:FILEPATH=//p' "$BUILD/CMakeCache.txt")
if grep -q '^ENVPIS_BUILD_PYTHON:BOOL=ON' "$BUILD/CMakeCache.txt"; then
  MODULE=$(find "$PREFIX" -name 'envpis.cpython*.so' | head -n1)
  [ -n "$MODULE" ] || { echo "test-install: the Python module was not installed" >&2; exit 1; }
  echo "== import $MODULE"
  PYTHONPATH=$(dirname "$MODULE") "$PY" -c "import envpis, envpis_chi2; print('envpis', envpis.__version__, envpis.simd_name())"
fi
echo "== test-install: OK"
