#!/usr/bin/env bash
# Operator assembly table (issue 3): for every mesh of ../shared/data at 1024^2 and 2048^2, texels
# (interior / boundary), boundary cells, assembly time with 1 thread (wall and CPU: the CPU time is
# robust to other load on the machine) and 2 threads (best of two), and peak memory (after the
# first assembly: mesh, atlas, grid and one TexelOperators).
# Each row runs in a fresh process so that ru_maxrss is that mesh's peak (mesh + grid + operators).
# Usage: scripts/bench-operators.sh [build-dir]   (a Release build with bench_operators built)
set -euo pipefail
cd "$(dirname "$0")/.."
exe="${1:-build/release}/bench/bench_operators"
[[ -x "$exe" ]] || { echo "bench-operators: $exe not found; build the bench_operators target" >&2; exit 1; }
meshes=(spot/spot_triangulated.obj bob/bob_tri.obj blub/blub_triangulated.obj
        lpshead/head_triangulated.obj ycb_scissors/textured_simple_reoriented.obj
        BoomBox/obj/BoomBox.obj WaterBottle/obj/WaterBottle.obj Lantern/obj/Lantern.obj
        Avocado/obj/Avocado.obj Suzanne/obj/Suzanne.obj)
echo "# $(date -u +%FT%TZ), load: $(uptime | sed 's/.*load average: //'), $(nproc) cores"
printf '| %-12s | %5s | %9s | %8s | %8s | %7s | %7s | %7s | %8s | %8s |\n' mesh res interior \
  boundary "b.cells" "1 thr s" "1 thr cpu" "2 thr s" "seam pcs" "peak MB"
printf '|%s|\n' "--------------|-------|-----------|----------|----------|---------|---------|---------|----------|----------"
for mesh in "${meshes[@]}"; do
  for res in 1024 2048; do
    read -r r interior boundary cells one cpu two seam peak < <("$exe" --table "$mesh" "$res")
    printf '| %-12s | %5s | %9s | %8s | %8s | %7s | %7s | %7s | %8s | %8s |\n' "${mesh%%/*}" \
      "$r" "$interior" "$boundary" "$cells" "$one" "$cpu" "$two" "$seam" "$peak"
  done
done
