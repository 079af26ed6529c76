#!/usr/bin/env bash
# Builds the browser page of `texgrad view` into viewer/dist (npm ci unless --no-install; needs
# Node.js and npm: scripts/install-deps.sh --viewer). The C++ build does not need this step.
set -euo pipefail
cd "$(dirname "$0")/../viewer"
if [[ "${1:-}" != "--no-install" ]]; then
  npm ci --no-audit --no-fund --loglevel=error
fi
node build.mjs
