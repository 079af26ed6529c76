#!/usr/bin/env bash
# Time and peak memory of `texgrad project` and `texgrad texture` on spot at 2048 x 2048 with 10
# synthetic 12 MP photos (issue 29). Needs a build with -DTEXGRAD_BUILD_BENCH=ON (photo_capture
# renders the photos once into $TMPDIR/texgrad-bench-photo; delete it to re-render).
#   scripts/bench-photo.sh [BUILD_DIR=build/rel] [VIEWS=10] [WIDTH=4000] [HEIGHT=3000] [TEXELS=2048]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/rel}"
views="${2:-10}" width="${3:-4000}" height="${4:-3000}" texels="${5:-2048}"
data="${TEXGRAD_SHARED_DATA:-../shared/data}"
work="${TMPDIR:-/tmp}/texgrad-bench-photo-${views}x${width}x${height}"
mesh="$data/spot/spot_triangulated.obj"
if [ ! -f "$work/sparse/images.txt" ]; then
  "$build/bench/photo_capture" "$mesh" "$data/spot/spot_texture.png" "$work" "$views" "$width" \
    "$height"
fi
run() {  # name, then the texgrad arguments
  local name="$1"
  shift
  /usr/bin/time -f "%e %M" -o "$work/$name.time" "$build/texgrad" "$@" --json -q \
    > "$work/$name.json"
  read -r seconds kib < "$work/$name.time"
  printf '%-8s %8.1f s  peak %6.0f MiB  stages %s\n' "$name" "$seconds" "$((kib / 1024))" \
    "$(tr -d ' \n' < "$work/$name.json" | grep -o '"stages":{[^}]*}')"
}
echo "spot at ${texels}^2, $views photos of ${width}x${height}"
run project project "$mesh" --cameras "$work/sparse" --images "$work/images" \
  --resolution "$texels" --out-dir "$work/views"
run texture texture "$mesh" --cameras "$work/sparse" --images "$work/images" \
  --resolution "$texels" --out "$work/texture.png"
# The partials: what texture holds of the views between projection and stitching (colour and
# confidence at the texels each view sees, float: --json partials_bytes), and for comparison the
# same views as the full-size float images project makes before writing them.
held=$(tr -d ' \n' < "$work/texture.json" | grep -o '"partials_bytes":[0-9]*' | cut -d: -f2)
read -r _ peak < "$work/texture.time"
echo "partials held by texture: $((held / 1048576)) MiB (seen texels only; as full-size float" \
  "images they would be $((views * texels * texels * 16 / 1048576)) MiB)"
echo "texture peak $((peak / 1024)) MiB = 1024 MiB + partials + $((peak / 1024 - 1024 - \
  held / 1048576)) MiB"
