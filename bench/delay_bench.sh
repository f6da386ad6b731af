#!/usr/bin/env bash
# The continuous loop with dead time, fast and lean (docs/benchmarks.md,
# "Dead time, fast and lean"), in one run:
#   1. one evaluation of the tuner's objective on three delayed loops, the
#      fast path (ObjectiveEvaluator) against the reference path (the loop as
#      computed before: Nyquist count, method of steps node by node):
#      evaluations/s, ratio, relative difference (delay_bench's table);
#   2. the peak RSS (/usr/bin/time -v) of a multi-start search of 200
#      evaluations on 1/(10s+1) e^(-2s) on either path (delay_bench --tune=...),
#      and of the command it stands for, `pidlab tune --num 1 --den 10,1
#      --delay 2 --method multi-start --max-evals 200`.
# Builds nothing.
#   bench/delay_bench.sh [BUILD_DIR]   (default build)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
bench=$build/bin/delay_bench
pidlab=$build/bin/pidlab
for x in "$bench" "$pidlab"; do
  [ -x "$x" ] || { echo "delay_bench.sh: $x is not an executable (ninja -C $build delay_bench pidlab)" >&2; exit 2; }
done
[ -x /usr/bin/time ] || { echo "delay_bench.sh: /usr/bin/time is missing (apt-get install time)" >&2; exit 2; }

"$bench" --benchmark_min_time=0.5

# Peak RSS in kB and wall time of a command, its own output's first line.
measure() {
  local log
  log=$(mktemp)
  /usr/bin/time -v "$@" >"$log.out" 2>"$log"
  printf '%-44s peak RSS %8s kB  wall %s  | %s\n' "$*" \
    "$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$log")" \
    "$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$log")" \
    "$(head -n 2 "$log.out" | tail -n 1 | cut -c1-100)"
  rm -f "$log" "$log.out"
}
echo
echo "peak RSS of a delayed tune (200 evaluations):"
measure "$bench" --tune=reference
measure "$bench" --tune=fast
measure "$pidlab" tune --num 1 --den 10,1 --delay 2 --method multi-start --max-evals 200
