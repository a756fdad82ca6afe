#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Checks the installed CMake package the way an outside project sees it: installs BUILD_DIR into a
# temporary prefix, checks its version file accepts the build's minor version and refuses the others,
# configures examples/minimal against it (find_package(envpis 0.2 CONFIG REQUIRED)), builds it and runs
# it (it prints the library's version). Fails on any error. Usage: scripts/test-install.sh BUILD_DIR
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
for f in envpisConfig.cmake envpisConfigVersion.cmake version.h; do
  find "$PREFIX" -name "$f" | grep -q . || { echo "test-install: $f was not installed" >&2; exit 1; }
done
VERSION=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$BUILD/CMakeCache.txt")
[[ $VERSION =~ ^([0-9]+)\.([0-9]+)\.[0-9]+$ ]] \
  || { echo "test-install: no project version in $BUILD/CMakeCache.txt" >&2; exit 1; }
MAJOR=${BASH_REMATCH[1]} MINOR=${BASH_REMATCH[2]}

# The version file: a bare project asks for several versions. 0.x: SameMinorVersion, so the previous and
# next minor versions and the next major one are refused (CXX: an accepted one loads envpisConfig.cmake,
# whose find_dependency(TBB) needs a language).
echo "== find_package(envpis X CONFIG) against $VERSION"
mkdir -p "$TMP/probe"
cat >"$TMP/probe/CMakeLists.txt" <<'PROBE'
cmake_minimum_required(VERSION 3.20)
project(envpis_version_probe LANGUAGES CXX)
find_package(envpis ${REQUEST} CONFIG QUIET)
message(STATUS "probe: envpis ${REQUEST}: found=${envpis_FOUND}")
PROBE
probe() {  # probe REQUEST EXPECTED(1|0)
  local out found
  out=$(cmake -S "$TMP/probe" -B "$TMP/probe-build-$1" -DREQUEST="$1" -DCMAKE_PREFIX_PATH="$PREFIX" \
        -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON 2>&1) || { echo "$out"; exit 1; }
  found=$(sed -n 's/.*probe: envpis .*: found=\(.*\)$/\1/p' <<<"$out")
  if { [ "$2" = 1 ] && [ "$found" != 1 ]; } || { [ "$2" = 0 ] && [ "$found" = 1 ]; }; then
    echo "$out" >&2
    echo "test-install: find_package(envpis $1) gave found='$found' against $VERSION, expected $2" >&2
    exit 1
  fi
  echo "find_package(envpis $1): found=${found:-0} (expected $2)"
}
probe "$MAJOR.$MINOR" 1
probe "$VERSION" 1
if [ "$MINOR" -gt 0 ]; then probe "$MAJOR.$((MINOR - 1))" 0; fi
probe "$MAJOR.$((MINOR + 1))" 0
probe "$((MAJOR + 1)).0" 0

echo "== configure and build examples/minimal against the installed package"
GEN=()
if command -v ninja >/dev/null; then GEN=(-G Ninja); fi
cmake -S "$SRC/examples/minimal" -B "$TMP/build" "${GEN[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON
cmake --build "$TMP/build"

echo "== run"
"$TMP/build/envpis_minimal" | tee "$TMP/run.log"
grep -qx "envpis $VERSION (headers $VERSION)" "$TMP/run.log" \
  || { echo "test-install: envpis_minimal did not print 'envpis $VERSION (headers $VERSION)'" >&2; exit 1; }

# The Python module, when the build has it: installed under the prefix and importable from there.
PY=$(sed -n 's/^Python3_EXECUTABLE:FILEPATH=//p' "$BUILD/CMakeCache.txt")
if grep -q '^ENVPIS_BUILD_PYTHON:BOOL=ON' "$BUILD/CMakeCache.txt"; then
  MODULE=$(find "$PREFIX" -name 'envpis.cpython*.so' | head -n1)
  [ -n "$MODULE" ] || { echo "test-install: the Python module was not installed" >&2; exit 1; }
  echo "== import $MODULE"
  PYTHONPATH=$(dirname "$MODULE") "$PY" -c "import envpis, envpis_chi2; print('envpis', envpis.__version__, envpis.simd_name())" \
    | tee "$TMP/python.log"
  grep -q "^envpis $VERSION " "$TMP/python.log" \
    || { echo "test-install: the installed module's __version__ is not $VERSION" >&2; exit 1; }
fi
echo "== test-install: OK"
