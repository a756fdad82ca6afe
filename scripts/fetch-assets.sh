#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Fetches the CC0 models and HDRIs of the asset scenes (docs/assets.md) from the npm package
# @pmndrs/assets, which stores each file base64-encoded inside a .js module, and decodes them into a
# cache outside the repository:
#   ${ENVPIS_ASSETS:-${XDG_CACHE_HOME:-$HOME/.cache}/envpis/assets}/{bunny.glb, suzi.glb, hdri/*.exr,
#   normals/*.webp, LICENSE, interiors/*.gltf}
# The interior rooms (interiors/, issue 24) are not fetched: scripts/make-interiors.py writes them, on
# every run (they are small, and deterministic).
# Scene files name that directory ${ENVPIS_ASSETS} (docs/scene-format.md). Idempotent: does nothing
# when the pinned version is already decoded. Needs node and npm (scripts/install-deps.sh).
set -euo pipefail
VERSION=1.7.0
DEST=${ENVPIS_ASSETS:-${XDG_CACHE_HOME:-$HOME/.cache}/envpis/assets}
STAMP="$DEST/.pmndrs-assets-$VERSION"
python3 "$(dirname "$0")/make-interiors.py" "$DEST/interiors"
if [ -f "$STAMP" ]; then
  echo "fetch-assets: @pmndrs/assets $VERSION already in $DEST"
  exit 0
fi
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
echo "fetch-assets: fetching @pmndrs/assets@$VERSION with npm"
(cd "$TMP" && npm pack "@pmndrs/assets@$VERSION" --silent --no-audit --no-fund >/dev/null)
tar xzf "$TMP"/pmndrs-assets-"$VERSION".tgz -C "$TMP"
mkdir -p "$DEST/hdri" "$DEST/normals"
# Each module is `export default 'data:<mime>;base64,<payload>'`.
node - "$TMP/package" "$DEST" <<'JS'
const fs = require('fs'), path = require('path');
const [src, dest] = process.argv.slice(2);
const files = [['models/bunny.glb', 'bunny.glb'], ['models/suzi.glb', 'suzi.glb'],
               ['normals/0000.webp', 'normals/0000.webp'], ['normals/0001.webp', 'normals/0001.webp']];
for (const f of fs.readdirSync(path.join(src, 'hdri')))
  if (f.endsWith('.exr.js')) files.push(['hdri/' + f.slice(0, -3), 'hdri/' + f.slice(0, -3)]);
for (const [from, to] of files) {
  const text = fs.readFileSync(path.join(src, from + '.js'), 'utf8');
  const m = text.match(/base64,([A-Za-z0-9+/=]+)/);
  if (!m) throw new Error(`fetch-assets: no base64 payload in ${from}.js`);
  fs.writeFileSync(path.join(dest, to), Buffer.from(m[1], 'base64'));
}
console.log(`fetch-assets: decoded ${files.length} files into ${dest}`);
JS
cp "$TMP/package/LICENSE" "$DEST/LICENSE"
touch "$STAMP"
