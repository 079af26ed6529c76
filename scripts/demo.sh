#!/usr/bin/env bash
# One command on a fresh Debian 12 box (as root): install, build, and run texgrad on the built-in
# sample (a torus with six charts and a procedural texture): atlas report, texel mask, seam-free
# smoothing and sharpening, geodesic distance; installs the Python module (`import texgrad`) and
# runs one of its examples. Output goes to out/sample/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build/release -DTEXGRAD_BUILD_PYTHON=ON
# The Python module for /usr/bin/python3 and the `python3` on PATH (docs/python.md).
bash scripts/install-python.sh build/release
tg=build/release/texgrad
mkdir -p out/sample
"$tg" sample --out-dir out/sample
"$tg" info out/sample/sample.obj --resolution 1024
"$tg" mask out/sample/sample.obj --resolution 1024 --kind chart --out out/sample/charts.png
"$tg" filter out/sample/sample.obj --beta 0 --out out/sample/smoothed.png --timings
"$tg" filter out/sample/sample.obj --beta 3 --out out/sample/sharpened.png --timings
"$tg" geodesic out/sample/sample.obj --source-vertex 0 --resolution 1024 \
  --out out/sample/distance.exr --png out/sample/distance.png --isolines 16
(cd / && python3 -c "import texgrad; print('python3: import texgrad', texgrad.__version__)")
python3 examples/python/smooth_texture.py --out out/sample/numpy_smoothed.png
echo "demo output in out/sample/:"
ls -1 out/sample
