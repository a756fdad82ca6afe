#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Cycles (Debian's Blender 3.4) side by side with envpis on the glTF asset scenes (scenes/assets-*.json):
# each renderer against its own converged reference, at equal time, per object and over the image. See
# docs/cycles.md, "The asset scenes", for the matched settings and what cannot match.
#
#   scripts/cycles-assets.sh [--install] [options of scripts/cycles_assets.py]
#   scripts/cycles-assets.sh --help
#
# As scripts/cycles-compare.sh: --install (or CYCLES_INSTALL=1) apt-gets Blender when it is missing,
# otherwise a missing Blender is one line and exit status 1; BUILD (default build) is the envpis build
# directory (envpis_cmd is built there if missing). The scenes' models come from Debian's
# assimp-testmodels and scripts/fetch-assets.sh (ENVPIS_ASSETS, ENVPIS_ASSIMP_MODELS as envpis reads
# them). Results go to out/cycles-assets/ (git-ignored) unless --out says otherwise.
exec bash "$(dirname "$0")/cycles-run.sh" cycles-assets scripts/cycles_assets.py "$@"
