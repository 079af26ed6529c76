#!/usr/bin/env bash
# Builds Release and runs every benchmark, then prints one summary table (name, time, counters).
# Figures depend on the machine; compare rows measured in the same run (e.g. multigrid vs direct).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build/release -DTEXGRAD_WERROR=ON
mkdir -p out/bench
for exe in build/release/bench/bench_*; do
  name="$(basename "$exe")"
  echo "== $name" >&2
  "$exe" --benchmark_format=json --benchmark_out="out/bench/$name.json" \
    --benchmark_out_format=json >/dev/null
done
python3 - <<'PY'
import glob, json
rows = []
for path in sorted(glob.glob("out/bench/bench_*.json")):
    for b in json.load(open(path))["benchmarks"]:
        if b.get("run_type") == "aggregate":
            continue
        extra = {k: v for k, v in b.items() if k not in (
            "name", "family_index", "per_family_instance_index", "run_name", "run_type",
            "repetitions", "repetition_index", "threads", "iterations", "real_time", "cpu_time",
            "time_unit", "aggregate_name", "aggregate_unit", "label")}
        counters = ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                             for k, v in extra.items())
        rows.append((b["name"], f'{b["real_time"]:.1f} {b["time_unit"]}', counters))
width = max(len(r[0]) for r in rows) if rows else 10
print(f'{"benchmark":<{width}}  {"wall time":>14}  counters')
for name, t, c in rows:
    print(f"{name:<{width}}  {t:>14}  {c}")
PY
