#!/usr/bin/env bash
# Loss recovery at network speed: one episode of 25 s at dt = 1 ms (25,000
# lockstep steps of the double integrator, gains 2,1,1.5) per drop rate, each
# in its own private network namespace (`pidlab launch --isolated --drop-rate
# F`: every process throws away the fraction F of the messages it receives).
# Prints the wall time of the episode (`pidlab evaluate --backend lcm`, from
# start to exit), its ratio to the clean episode, the plant's measured round
# trip and resend timeout and its resends, and whether the IAE is the same bits
# as the in-process sampled loop (`pidlab evaluate --loop sampled`).
#   bench/loss_bench.sh [BIN_DIR] [RATE...]     (root; default rates 0 0.05 0.1 0.2 0.3)
# EVAL_ARGS overrides the episode's flags. Prints a Markdown table for docs/trio.md.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-build/bin}")
shift || true
rates=("$@")
[ ${#rates[@]} -gt 0 ] || rates=(0 0.05 0.1 0.2 0.3)
eval_args=${EVAL_ARGS:---plant double_integrator --gains 2,1,1.5 --loop sampled --dt 1e-3 --horizon 25}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin/pidlab" evaluate $eval_args --json > "$tmp/local.json"
local_iae=$(python3 -c 'import json,sys; print(repr(json.load(open(sys.argv[1]))["iae"]))' "$tmp/local.json")
echo "in-process IAE $local_iae; load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
export eval_args tmp
echo "| drop rate | episode (s) | ratio to 0 % | plant resends | round trip, resend timeout (us) | IAE bit-identical |"
echo "|---|---|---|---|---|---|"
clean=""
for rate in "${rates[@]}"; do
  echo "drop rate $rate ..." >&2
  "$bin/pidlab" launch --isolated --drop-rate "$rate" -- bash -c '
    start=$(date +%s.%N)
    pidlab evaluate --backend lcm $eval_args --json > "$tmp/lcm.json"
    end=$(date +%s.%N)
    echo "$start $end" > "$tmp/wall"' 2> "$tmp/launch.err" || { cat "$tmp/launch.err" >&2; exit 1; }
  wall=$(awk '{printf "%.2f", $2 - $1}' "$tmp/wall")
  [ -n "$clean" ] || clean=$wall
  iae=$(python3 -c 'import json,sys; print(repr(json.load(open(sys.argv[1]))["iae"]))' "$tmp/lcm.json")
  same=$([ "$iae" = "$local_iae" ] && echo yes || echo "NO ($iae)")
  # pidlab-plant: episode ID: done, ... (resent R, dropped D, round trip T us, resend timeout O us)
  line=$(grep 'pidlab-plant: episode .*done' "$tmp/launch.err" | tail -1)
  resent=$(sed -n 's/.*(resent \([0-9]*\),.*/\1/p' <<<"$line")
  rtt=$(sed -n 's/.*round trip \([0-9]*\) us, resend timeout \([0-9]*\) us.*/\1, \2/p' <<<"$line")
  echo "| $(awk -v r="$rate" 'BEGIN{printf "%g %%", 100 * r}') | $wall | $(awk -v a="$wall" -v b="$clean" 'BEGIN{printf "%.2f", a / b}') | ${resent:-?} | ${rtt:-?} | $same |"
  [ "$same" = yes ] || { echo "drop rate $rate: IAE $iae differs from the in-process $local_iae" >&2; exit 1; }
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" >&2
