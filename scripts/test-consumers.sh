#!/usr/bin/env bash
# texgrad as an outside project sees it: tests/consumer built three ways, each run on spot and its
# output compared byte for byte with `texgrad filter MESH TEXTURE --beta 0`'s:
#  (a) find_package(texgrad CONFIG) against a prefix made by `cmake --install BUILD` (static);
#  (b) pkg-config on a plain g++ command line, against the same prefix;
#  (c) add_subdirectory of this source tree from a parent that sets no C++ standard, texgrad
#      library-only and shared: no CLI, viewer or tests, CLI11 and Boost made unfindable (so it is
#      also the library-only build). Its compile commands equal BUILD's (Release, -Werror) but for
#      the object paths, which ccache leaves out of its hash: through BUILD's launcher (ccache in
#      scripts/test.sh) it reuses BUILD's objects.
# Also: a parent configured without a build type keeps none (texgrad sets one only at the top
# level), and the installed `texgrad view` serves the installed page (when BUILD bundled it).
# Usage: scripts/test-consumers.sh [BUILD]   (a Release build with the CLI; default build/release)
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
build="${1:-build/release}"
work="$PWD/$build/consumers"
data="${TEXGRAD_SHARED_DATA:-$(cd .. && pwd)/shared/data}"
mesh="$data/spot/spot_triangulated.obj"
texture="$data/spot/spot_texture.png"
mkdir -p "$work"
# README's "Use as a library" shows the consumer program: the two must not drift apart.
awk '/tests\/consumer\/filter_texture.cpp`\):$/ {found = 1; next}
     found && /^```cpp$/ {inside = 1; next}
     inside && /^```$/ {exit}
     inside {print}' README.md | diff -u - tests/consumer/filter_texture.cpp
"$build/texgrad" filter "$mesh" "$texture" --beta 0 --out "$work/expected.png" --quiet

# check NAME PROGRAM: runs PROGRAM on spot; its image must equal texgrad filter's, byte for byte.
check() {
  "$2" "$mesh" "$texture" "$work/$1.png" >/dev/null
  cmp "$work/expected.png" "$work/$1.png"
  echo "consumer $1: output identical to texgrad filter's"
}

echo "== consumer (a): find_package(texgrad CONFIG) against cmake --install $build"
prefix="$work/prefix"
rm -rf "$prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
pc="$(find "$prefix" -name texgrad.pc)"
for file in bin/texgrad include/texgrad/apps/filter.h "${pc#"$prefix/"}"; do
  [[ -f "$prefix/$file" ]] || { echo "test-consumers: $file not installed" >&2; exit 1; }
done
cmake --no-warn-unused-cli -S tests/consumer -B "$work/find-package" -G Ninja \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
ninja -C "$work/find-package" >/dev/null
check find-package "$work/find-package/filter_texture"
# CHOLMOD is LGPL (and GPL in parts): it must stay a shared library, never linked in.
ldd "$work/find-package/filter_texture" | grep -q 'libcholmod\.so'

echo "== consumer (b): pkg-config and g++"
mkdir -p "$work/pkg-config"
# shellcheck disable=SC2046  # pkg-config prints several words on purpose
g++ -std=c++20 -O2 tests/consumer/filter_texture.cpp -o "$work/pkg-config/filter_texture" \
  $(PKG_CONFIG_PATH="$(dirname "$pc")" pkg-config --cflags --libs --static texgrad)
check pkg-config "$work/pkg-config/filter_texture"

echo "== consumer (c): add_subdirectory, library only, shared"
library_only=(-DTEXGRAD_SOURCE_DIR="$PWD" -DTEXGRAD_BUILD_CLI=OFF -DTEXGRAD_BUILD_VIEWER=OFF
  -DTEXGRAD_BUILD_TESTS=OFF -DCMAKE_DISABLE_FIND_PACKAGE_CLI11=ON
  -DCMAKE_DISABLE_FIND_PACKAGE_Boost=ON)
subdirectory="$(dirname "$build")/consumer-subdirectory"
# BUILD's compiler launcher too (none if BUILD has none, whatever the environment says).
launcher="$(sed -n 's/^CMAKE_CXX_COMPILER_LAUNCHER:[A-Z]*=//p' "$build/CMakeCache.txt")"
cmake --no-warn-unused-cli -S tests/consumer -B "$subdirectory" -G Ninja \
  -DCMAKE_BUILD_TYPE=Release -DBUILD_SHARED_LIBS=ON -DTEXGRAD_WERROR=ON "${library_only[@]}" \
  -DCMAKE_CXX_COMPILER_LAUNCHER="$launcher" >/dev/null
ninja -C "$subdirectory" -j"$(nproc)" >/dev/null
ldd "$subdirectory/filter_texture" | grep -q 'libtexgrad_apps\.so'
check subdirectory "$subdirectory/filter_texture"
# A parent without a build type keeps none (tests/consumer/CMakeLists.txt fails otherwise).
cmake --no-warn-unused-cli -S tests/consumer -B "$work/no-build-type" -G Ninja \
  "${library_only[@]}" >/dev/null
grep -qx 'CMAKE_BUILD_TYPE:STRING=' "$work/no-build-type/CMakeCache.txt"

page="$prefix/share/texgrad/viewer"
if [[ -f "$page/index.html" ]]; then
  echo "== installed texgrad view"
  "$prefix/bin/texgrad" view builtin:square --port 0 >"$work/view.out" 2>"$work/view.err" &
  server=$!
  for _ in $(seq 300); do
    grep -q 'open http' "$work/view.out" || ! kill -0 "$server" 2>/dev/null && break
    sleep 0.2
  done
  kill "$server" 2>/dev/null || true
  wait "$server" || true
  if ! grep -q 'open http' "$work/view.out" || ! grep -qF "page from $page" "$work/view.err"; then
    echo "test-consumers: the installed texgrad view did not serve $page:" >&2
    cat "$work/view.err" >&2
    exit 1
  fi
  echo "installed texgrad view: serves $page"
fi
echo "consumers: $((SECONDS - start)) s"
