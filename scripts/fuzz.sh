#!/usr/bin/env bash
# Fuzzes every reader a user's file reaches: scripts/fuzz.sh [seconds-per-target] (default 45).
# Builds the libFuzzer targets of fuzz/ with clang-14, ASan and UBSan in build/fuzz (only them:
# no CLI, tests or benchmarks), builds seed corpora from the shared meshes at run time
# (fuzz/make-seeds.py), then runs each target for the given time, $(nproc) at a time. Fails on
# any crash, leak, hang (-timeout), memory blow-up (-rss_limit_mb) or sanitizer report; the input
# is then copied into fuzz/regressions/<target>/ (commit it: the normal suite replays it, CTest
# FuzzRegressions.<target>). Each target's log line shows its executions.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-45}"
build="${TEXGRAD_FUZZ_BUILD:-build/fuzz}"
shared="${TEXGRAD_SHARED_DATA:-../shared/data}"
started=$SECONDS

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# -O1 as in the sanitizer test build: quick to compile, still fast enough to fuzz.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS="-O1 -g1" \
  -DCMAKE_CXX_COMPILER=clang++-14 "${launcher[@]}" -DTEXGRAD_BUILD_FUZZ=ON \
  -DTEXGRAD_BUILD_CLI=OFF -DTEXGRAD_BUILD_VIEWER=OFF -DTEXGRAD_BUILD_TESTS=OFF \
  -DTEXGRAD_BUILD_BENCH=OFF -DTEXGRAD_INSTALL=OFF >/dev/null
ninja -C "$build" -j"$(nproc)" texgrad_fuzz
echo "fuzz build: $((SECONDS - started)) s"

run="$build/run"
rm -rf "$run"
mkdir -p "$run"
python3 fuzz/make-seeds.py "$shared" "$run/seeds"
targets=()
for program in "$build"/fuzz/fuzz_*; do targets+=("${program##*/fuzz_}"); done

# One target: fresh corpus + seeds + every input that ever crashed it; its log in $run/<t>.log.
fuzz_one() {
  local target="$1" corpus="$run/corpus/$1"
  mkdir -p "$corpus" "$run/seeds/$target"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    "$build/fuzz/fuzz_$target" "$corpus" "$run/seeds/$target" "fuzz/regressions/$target" \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$run/$target-" >"$run/$target.log" 2>&1
}

failed=0
pids=()
names=()
for target in "${targets[@]}"; do
  fuzz_one "$target" &
  pids+=($!)
  names+=("$target")
  if ((${#pids[@]} >= $(nproc))); then
    wait "${pids[0]}" || true
    pids=("${pids[@]:1}")
  fi
done
wait || true

for target in "${targets[@]}"; do
  log="$run/$target.log"
  executions="$(grep -o 'number_of_executed_units: [0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)"
  crashes=("$run/$target"-*)
  if grep -qE '^==[0-9]+==ERROR|runtime error:|^SUMMARY: |deadly signal|ALARM: working' "$log" ||
    ! grep -q '^Done [0-9]* runs' "$log" || [[ -e "${crashes[0]}" ]]; then
    echo "fuzz_$target: FAILED after $executions executions; log $log"
    grep -E 'ERROR|runtime error|SUMMARY|ALARM|deadly' "$log" | head -5
    mkdir -p "fuzz/regressions/$target"
    for crash in "${crashes[@]}"; do
      [[ -e "$crash" ]] || continue
      cp "$crash" "fuzz/regressions/$target/"
      echo "  kept fuzz/regressions/$target/${crash##*/}: fix it, then commit it"
    done
    failed=1
  else
    echo "fuzz_$target: $executions executions in $seconds s, no findings"
  fi
done
echo "fuzz step: $((SECONDS - started)) s in total (${#targets[@]} targets x $seconds s)"
exit "$failed"
