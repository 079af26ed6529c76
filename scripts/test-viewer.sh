#!/usr/bin/env bash
# Viewer end-to-end tests in headless Chromium (and, with --bench, the updates/s benchmark).
# Usage: scripts/test-viewer.sh BUILD_DIR [--bench]. Installs Node.js, npm and Chromium (Debian)
# and the page's npm packages if missing; needs ../shared/data (spot).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/release}"
bash scripts/install-deps.sh --viewer
bash scripts/build-viewer.sh
export TEXGRAD_CLI="$PWD/$build/texgrad" TEXGRAD_E2E_OUT="$PWD/$build/e2e"
timeout 600 node tests/e2e/run-all.mjs
if [[ "${2:-}" == "--bench" ]]; then
  timeout 300 node --experimental-websocket tests/e2e/bench-updates.mjs
fi
