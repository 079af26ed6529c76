#!/usr/bin/env bash
# One command on a fresh Debian 12 box (as root): install, build, and run texgrad on the built-in
# sample. Output goes to out/sample/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build/release
tg=build/release/texgrad
mkdir -p out/sample
"$tg" sample --out-dir out/sample
"$tg" info out/sample/sample.obj --resolution 1024
"$tg" mask out/sample/sample.obj --resolution 1024 --kind chart --out out/sample/charts.png
echo "demo output in out/sample/:"
ls -1 out/sample
