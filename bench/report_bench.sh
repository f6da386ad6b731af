#!/usr/bin/env bash
# Wall time of the whole `pidlab report` (Tables II-VI, every tuning, the
# figures and the 25 s LCM trio episode in its private namespace), N runs.
# The target: under a minute on the 2-core machine.
#   bench/report_bench.sh [N=3] [PIDLAB=build/bin/pidlab]
set -euo pipefail
n=${1:-3}
pidlab=${2:-$(dirname "$0")/../build/bin/pidlab}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
times=()
for i in $(seq "$n"); do
  start=$(date +%s%N)
  "$pidlab" report --out "$out/r$i" >/dev/null
  end=$(date +%s%N)
  ms=$(( (end - start) / 1000000 ))
  times+=("$ms")
  echo "run $i: $(( ms / 1000 )).$(printf '%03d' $(( ms % 1000 ))) s"
done
median=$(printf '%s\n' "${times[@]}" | sort -n | sed -n "$(( (n + 1) / 2 ))p")
echo "median: $(( median / 1000 )).$(printf '%03d' $(( median % 1000 ))) s over $n runs (target < 60 s)"
