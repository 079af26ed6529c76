#!/usr/bin/env bash
# One command on a fresh Debian 12 box (as root): install, build with warnings as errors, and run
# the fast tests under AddressSanitizer+UBSan (less five costly checks, below); then, in Release,
# the Python module's tests and examples (pytest), the consumer builds (scripts/test-consumers.sh:
# an outside project against the installed package by find_package, pkg-config and add_subdirectory
# of a library-only shared build), the fuzzing of every file reader, the camera files and the
# viewer's message parser (scripts/fuzz.sh: libFuzzer, ASan + UBSan), the solver's fast tests again
# (its SIMD kernels exist only there), the tests too slow for the sanitizer build (named *Slow*:
# full-size shared meshes), the allocator tests the sanitizers exclude, the glTF validator test (npm
# gltf-validator) and the viewer page's tests, including its end-to-end tests in headless Chromium
# (ViewerE2E). `ctest --test-dir build/release` afterwards runs the whole suite in Release.
# --no-label-summary keeps ctest's "tests passed" summary the last thing printed (tests carry module
# labels).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh --viewer
echo "== viewer page (npm ci in viewer/)"
bash scripts/build-viewer.sh
echo "== glTF validator (npm ci in tests/gltf-validator/, for CTest GltfOutputsValidate)"
(cd tests/gltf-validator && npm ci --no-audit --no-fund --loglevel=error)
jobs="$(nproc)"

echo "== sanitizer build (ASan + UBSan)"
# -O1 keeps the sanitizer build quick to compile and its tests quick to run; tests named *Slow*
# (full-size shared meshes) run only in the Release pass below. TEXGRAD_BUILD_VIEWER is explicit:
# build trees configured before it meant the viewer module (it used to mean the page) cached OFF.
# Five of GCC's UBSan checks are left out here: on the two translation units measured they took
# 37-47% of the compile time (multigrid_solver.cpp 22.4 -> 11.8 s, the largest test batch 69.8 ->
# 43.9 s; the whole build 800 -> 521 s, its tests 459 -> 371 s). What they would find is partly
# covered otherwise, not wholly: null (a dereference that faults, ASan reports it; a member call
# or reference through null that does not fault goes unseen), object-size (ASan's redzones catch
# an access just past an object, not one far beyond it), alignment (Eigen asserts the alignment
# of its own fixed-size objects in this NDEBUG-less build), pointer-overflow and vptr (wrapping
# pointer arithmetic and wrong dynamic types: no cover, and little risk in this code, whose only
# class hierarchies are the viewer's apps and the error types, thrown and caught but never cast).
# The fuzz build below keeps clang's full -fsanitize=undefined on every file reader.
bash scripts/build.sh build/asan -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS="-O1 -g1" \
  -DTEXGRAD_SANITIZE=ON -DTEXGRAD_SANITIZE_SKIP=vptr,null,alignment,object-size,pointer-overflow \
  -DTEXGRAD_WERROR=ON -DTEXGRAD_BUILD_BENCH=OFF -DTEXGRAD_BUILD_VIEWER=ON
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build/asan -j"$jobs" --output-on-failure --no-label-summary -E 'Slow'

echo "== release build"
# Through ccache, so that the consumers' library-only build (scripts/test-consumers.sh, same
# compile commands) takes its objects from this one instead of compiling them again (the
# consumers' step took 189 s before, 29 s after). Depend mode: a miss compiles once, without
# running the preprocessor first.
CCACHE_DEPEND=true bash scripts/build.sh build/release -DTEXGRAD_WERROR=ON \
  -DTEXGRAD_BUILD_VIEWER_PAGE=ON -DTEXGRAD_E2E_TESTS=ON -DTEXGRAD_GLTF_VALIDATOR_TESTS=ON \
  -DTEXGRAD_BUILD_PYTHON=ON -DCMAKE_CXX_COMPILER_LAUNCHER=ccache
# The Python module: installed as the README's set-up does (python3 on PATH may be another 3.11,
# docs/python.md), then its tests and examples with pytest (module from build/release/python).
echo "== Python module (pytest)"
bash scripts/install-python.sh build/release
(cd / && python3 -c "import texgrad; print('python3: import texgrad', texgrad.__version__)")
TEXGRAD_BUILD_DIR=build/release PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 -m pytest -q \
  -p no:cacheprovider python/tests
echo "== consumers (install, find_package, pkg-config, add_subdirectory)"
bash scripts/test-consumers.sh build/release
# Fuzz every reader a user's file reaches (clang-14 libFuzzer, ASan + UBSan) for 45 s a target,
# two at a time: 5 min on 2 cores, build included (295 s measured: 108 s build, through ccache with
# an empty cache).
echo "== fuzzing (scripts/fuzz.sh)"
bash scripts/fuzz.sh 45
# The solver's row kernels are compiled for AVX2 and AVX-512 only without the sanitizers
# (src/solver/grid_kernels.h), so the solver's fast tests run again here on the kernels users get.
ctest --test-dir build/release -j"$jobs" --output-on-failure --no-label-summary -L '^solver$'
# The other fast tests already passed under the sanitizers above (the stricter check); running
# them again here would add about two minutes to CI. HeapReuse's glibc-malloc tests and
# PageAllocator's mapped blocks exist only without the sanitizers (which replace malloc and keep
# every block in their own heap), so they run here.
ctest --test-dir build/release -j"$jobs" --output-on-failure --no-label-summary \
  -R 'Slow|HeapReuse|PageAllocator|ViewerPageUnits|ViewerE2E|GltfOutputsValidate'
