#!/usr/bin/env bash
# Solver benchmark table (multigrid issue): every mesh of ../shared/data at 1024² and 2048², and
# spot at 4096², one process per row (so peak memory is per row). Columns: texels, levels,
# read / operator / multigrid init and update times, float and double V-cycle on RGB with 1 and 2
# threads, CHOLMOD full factorisation and solve, peak memory, and the relative error to the
# CHOLMOD solution after 1..6 float V-cycles (paper Fig. 11 set-up: alpha = 1e4, random psi).
# Usage: scripts/bench-solver.sh [RESOLUTIONS...]   (default: 1024 2048; spot also at 4096)
# Takes about half an hour on 2 cores; run it on a quiet machine.
set -euo pipefail
cd "$(dirname "$0")/.."
data="$(cd .. && pwd)/shared/data"
bash scripts/install-deps.sh
bash scripts/build.sh build/release -DTEXGRAD_WERROR=ON >/dev/null
table=build/release/bench/solver_table
resolutions=("${@:-1024 2048}")
meshes=$(grep -E '^\| [A-Za-z_]+ \| `' "$data/INDEX.md" |
  awk -F'|' '{gsub(/[ `]/, "", $2); gsub(/[ `]/, "", $3); print $2 "|" $3}')
"$table" --header
for res in ${resolutions[*]}; do
  for entry in $meshes; do
    name="${entry%%|*}"
    "$table" "$data/$name/${entry#*|}" "$res" --name "$name" ||
      echo "| $name | $res | failed (exit $?) |"
  done
done
if [[ $# -eq 0 ]]; then
  # CHOLMOD on 8.4M unknowns needs far more time and memory than the rest together: skipped.
  "$table" "$data/spot/spot_triangulated.obj" 4096 --name spot --no-direct
fi
