#!/usr/bin/env bash
# Pacing against the machine's own floor, back to back in one run: for each
# repetition, bench/wakeup_bench (one SCHED_FIFO thread at priority 50, memory
# locked, absolute clock_nanosleep every dt and nothing else: the floor) and
# then `pidlab launch --isolated --realtime` episodes of the same length at
# the same dt, by default with the priority launch chooses by itself (no
# --rt-priority: SCHED_FIFO 50 with --realtime, docs/trio.md). MODES=
# 'default|--rt-priority 10|--rt-priority 0' runs one episode per mode
# ('|'-separated launch flags, `default` for none) after each floor.
# Prints p50/p99/max lateness and late wake-ups / missed deadlines of both,
# the ratio of the trio's p99 to the floor's, and the machine's load before
# each row (a loaded machine moves both: compare within a row).
#   bench/pacing_bench.sh [BIN_DIR] [REPS=3] [SECONDS=10] [DT=0.001]   (root)
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) sed -n '2,13p' "$0"; exit 0 ;; esac
bin=$(realpath "${1:-build/bin}")
reps=${2:-3}; seconds=${3:-10}; dt=${4:-0.001}
for v in "$reps" "$seconds" "$dt"; do
  [[ "$v" =~ ^[0-9]*\.?[0-9]+([eE]-?[0-9]+)?$ ]] || { echo "pacing_bench: error: '$v' is not a positive number" >&2; exit 2; }
done
[ -x "$bin/wakeup_bench" ] || { echo "pacing_bench: error: no $bin/wakeup_bench (scripts/build.sh builds the benchmarks)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
IFS='|' read -r -a modes <<< "${MODES:-default}"
echo "| rep | load | floor p50 / p99 / max (us), late > dt | launch flags | trio p50 / p99 / max (us), missed | trio p99 / floor p99 |"
echo "|---|---|---|---|---|---|"
for rep in $(seq 1 "$reps"); do
  load=$(cut -d' ' -f1 /proc/loadavg)
  # "lateness p50 73 us, p99 886 us, max 18480 us; later than 200 us: 435; later than one period: 94"
  floor=$("$bin/wakeup_bench" "$dt" "$seconds" 50 2>&1 | grep 'lateness p50')
  read -r f50 f99 fmax flate <<< "$(sed -E 's/.*p50 ([0-9]+) us, p99 ([0-9]+) us, max ([0-9]+) us.*one period: ([0-9]+).*/\1 \2 \3 \4/' <<< "$floor")"
  for mode in "${modes[@]}"; do
    mode=$(xargs <<< "$mode")
    trio_flags=()
    [ "$mode" = default ] || read -r -a trio_flags <<< "$mode"
    "$bin/pidlab" launch --isolated --realtime "${trio_flags[@]}" -- pidlab evaluate --backend lcm \
      --plant double_integrator --gains 2,1,1.5 --loop sampled --dt "$dt" --horizon "$seconds" --json \
      > "$tmp/trio.json" 2> "$tmp/launch.err" || { cat "$tmp/launch.err" >&2; exit 1; }
    [ "$rep" != 1 ] || grep -h 'pidlab launch:' "$tmp/launch.err" | grep -E 'SCHED_FIFO|refused' >&2 || true
    /usr/bin/python3 - "$tmp/trio.json" "$rep" "$load" "$f50" "$f99" "$fmax" "$flate" "$mode" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["realtime"]
rep, load, f50, f99, fmax, flate, mode = sys.argv[2:]
t50, t99, tmax = (r[k] * 1e6 for k in ("lateness_p50_s", "lateness_p99_s", "lateness_max_s"))
print(f"| {rep} | {load} | {f50} / {f99} / {fmax}, {flate} | {mode} | {t50:.0f} / {t99:.0f} / {tmax:.0f}, "
      f"{r['missed_deadlines']} | {t99 / max(float(f99), 1.0):.2f} |", flush=True)
PY
  done
done
