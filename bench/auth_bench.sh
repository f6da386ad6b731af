#!/usr/bin/env bash
# The cost of --auth-key: lockstep steps/s of the trio without and with a key
# (HMAC-SHA256 on every message), interleaved RUNS times each in private
# network namespaces (pidlab launch --isolated), medians and their ratio.
#   bench/auth_bench.sh [RUNS] [HORIZON_S]     (root; after scripts/build.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-5} horizon=${2:-10}
bin=build/bin
key=$(mktemp); trap 'rm -f "$key"' EXIT
head -c 32 /dev/urandom > "$key"
plain=() keyed=()
for i in $(seq "$runs"); do
  plain+=("$("$bin/pidlab" launch --isolated -- "$bin/trio_bench" 2000 "$horizon" 2>/dev/null | awk '/lockstep trio/ {print $3}')")
  keyed+=("$("$bin/pidlab" launch --isolated --auth-key "$key" -- "$bin/trio_bench" 2000 "$horizon" 2>/dev/null |
    awk '/lockstep trio/ {print $3}')")
  echo "run $i/$runs: ${plain[-1]} steps/s without a key, ${keyed[-1]} with" >&2
done
median() { printf '%s\n' "$@" | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
p=$(median "${plain[@]}") k=$(median "${keyed[@]}")
echo "without a key  $p steps/s (median of $runs)"
echo "with a key     $k steps/s (median of $runs)"
echo "ratio          $(echo "scale=3; $k / $p" | bc)  (target >= 0.90: the key costs at most 10 %)"
