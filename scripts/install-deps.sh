#!/usr/bin/env bash
# Installs the Debian 12 packages texgrad needs to build, test and benchmark (run as root).
# With --viewer also Node.js, npm and Chromium for the viewer page and its end-to-end tests.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libsuitesparse-dev libtbb-dev
  # CHOLMOD's supernodal factorisation and solves run on BLAS (Debian's libblas.so.3
  # alternative): OpenBLAS instead of the reference BLAS makes a direct geodesic on spot at
  # 1024² 2.4x faster (18.1 -> 7.5 s). Its serial build starts no threads of its own next to TBB's.
  libopenblas0-serial
  # Image files: each format through its own library (src/io/image_codecs.h).
  libpng-dev libjpeg-dev libtiff-dev libopenexr-dev
  libtinyobjloader-dev libtinygltf-dev nlohmann-json3-dev libstb-dev
  # bench/memory.py upscales the shared textures with oiiotool.
  openimageio-tools
  libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev
  # scripts/test.sh compiles its Release build through ccache, which the consumer builds reuse.
  ccache
  libboost-dev
  # scripts/fuzz.sh: libFuzzer and the sanitizers' runtimes come with clang; seeds via Python.
  clang-14 libclang-rt-14-dev python3
  # The Python module (TEXGRAD_BUILD_PYTHON, docs/python.md): headers, pybind11, numpy and scipy
  # (sparse operators), pytest and tqdm (its tests), matplotlib (examples/python).
  python3-dev python3-pybind11 python3-numpy python3-scipy python3-pytest python3-tqdm
  python3-matplotlib
)
if [[ "${1:-}" == "--viewer" ]]; then
  # Debian's packages unless the commands are already there (e.g. Node.js from another source,
  # whose npm would conflict with Debian's).
  command -v node >/dev/null || packages+=(nodejs)
  command -v npm >/dev/null || packages+=(npm)
  command -v chromium >/dev/null || packages+=(chromium)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
