#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs the browser test's npm packages (tests/browser: playwright-core, which drives Debian's
# /usr/bin/chromium; no browser is downloaded) from tests/browser/package-lock.json. Idempotent: does
# nothing when the locked version is already installed. Needs node and npm (Debian: nodejs, npm).
set -euo pipefail
cd "$(dirname "$0")/../tests/browser"
want=$(node -e 'console.log(require("./package-lock.json").packages["node_modules/playwright-core"].version)')
have=$(node -e 'try { console.log(require("./node_modules/playwright-core/package.json").version) } catch { console.log("") }')
if [ "$want" = "$have" ]; then
  echo "install-node-deps: playwright-core $have already installed"
  exit 0
fi
echo "install-node-deps: installing playwright-core $want into tests/browser/node_modules"
PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error
