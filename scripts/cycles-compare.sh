#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Cycles (Debian's Blender 3.4) side by side with envpis on matched sphere scenes: each renderer against its
# own converged reference, at equal time. See docs/cycles.md for the matched settings and the conventions.
#
#   scripts/cycles-compare.sh [--install] [options of scripts/cycles_compare.py]
#   scripts/cycles-compare.sh --help
#
# Blender is large and CI never needs it, so it is installed only when asked: --install or CYCLES_INSTALL=1
# (apt-get install --no-install-recommends blender, as root or with sudo). Without it and without Blender,
# the script says so on one line and exits 1. BUILD (default build) is the envpis build directory: the
# script builds envpis_cmd there if the binary is missing. Results go to out/cycles-compare/ (git-ignored)
# unless --out says otherwise.
exec bash "$(dirname "$0")/cycles-run.sh" cycles-compare scripts/cycles_compare.py "$@"
