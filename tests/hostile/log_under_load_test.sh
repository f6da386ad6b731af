#!/usr/bin/env bash
# hostile.launch_log_keeps_every_configuration_under_load: `pidlab launch
# --log` keeps every episode's configuration on a machine with no CPU to
# spare. Two busy loops (the load of a `-j2` build) and a second trio that runs
# episodes without pause (on ports 7677-7679) run throughout; meanwhile RUNS
# launches of a trio with a log (ports 7667-7669) each run EVALUATIONS
# `pidlab evaluate --backend lcm` with a disturbance (two episodes each). For
# every run, launch must exit 0 and `pidlab replay --json` must list every
# episode the evaluations name (their -v notes) with its configuration and
# complete. Prints the runs passed, the seconds per run and how many runs
# launch had to restore a configuration in (lcm-logger lost every copy and the
# log got launch's own).
# Run as: unshare -n bash log_under_load_test.sh BIN_DIR [RUNS] [EVALUATIONS]
# (ctest does this; bench/log_under_load.sh runs it 50 times).
set -uo pipefail
bin=$(realpath -- "${1:?usage: log_under_load_test.sh BIN_DIR [RUNS] [EVALUATIONS]}")
runs=${2:-10}
evaluations=${3:-3}
for n in "$runs" "$evaluations"; do
  [[ "$n" =~ ^[1-9][0-9]{0,3}$ ]] || { echo "FAIL '$n' is not a count in 1..9999"; exit 2; }
done
pidlab=$bin/pidlab
here=$(dirname "$(realpath -- "${BASH_SOURCE[0]}")")

# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$here/../integration/lib.sh"
private_network_up
work=$(mktemp -d)
load=()
cleanup() {
  for pid in "${load[@]}"; do kill -- "$pid" 2>/dev/null; done
  wait 2>/dev/null
  [ -n "${KEEP:-}" ] || rm -rf "$work"
}
trap cleanup EXIT
cd "$work" || exit 1

# The load: two busy loops and a second trio running episodes back to back.
for _ in 1 2; do
  bash -c 'while :; do :; done' & load+=($!)
done
"$pidlab" launch --lcm-url "udpm://239.255.76.67:7677?ttl=0" -- bash -c '
  while :; do
    pidlab evaluate --backend lcm --plant oscillator --gains 3,1,1 --horizon 5 \
      --disturbance square --disturbance-amplitude 0.2 >/dev/null 2>&1 || exit 1
  done' >second.out 2>second.err & load+=($!)

url="udpm://239.255.76.67:7667?ttl=0"
passed=0
restored=0
episodes=0
start=$(date +%s%N)
for run in $(seq 1 "$runs"); do
  "$pidlab" launch --lcm-url "$url" --log "run$run.lcmlog" -- bash -c '
    for i in $(seq 1 "$1"); do
      pidlab evaluate --backend lcm -v --plant double_integrator --gains 2,1,1.5 --horizon 1 \
        --disturbance step --disturbance-amplitude 0.2 >/dev/null 2>>"$2.err" || exit 1
    done' launch "$evaluations" "run$run" >"run$run.out" 2>"run$run.launch.err"
  rc=$?
  ids=$(sed -n 's/^pidlab: note: episode \([0-9]*\) ran$/\1/p' "run$run.err" 2>/dev/null | tr '\n' ' ')
  grep -q "lcm-logger lost the configuration of episode" "run$run.launch.err" && restored=$((restored + 1))
  verdict=$("$pidlab" replay "run$run.lcmlog" --json 2>/dev/null | python3 -c '
import json, sys
ids = [int(i) for i in sys.argv[1].split()]
try:
    log = {e["episode_id"]: e for e in json.load(sys.stdin)["episodes"]}
except ValueError:
    log = {}
bad = [i for i in ids if i not in log or "config" not in log[i] or not log[i]["complete"]]
print("ok" if ids and not bad else "episodes %s of %d without their configuration or incomplete" % (bad, len(ids)))
' "$ids")
  if [ "$rc" -eq 0 ] && [ "$verdict" = ok ]; then
    passed=$((passed + 1))
    episodes=$((episodes + $(wc -w <<<"$ids")))
    rm -f "run$run.lcmlog"
  else
    echo "FAIL run $run: launch exited $rc; $verdict: $(tail -c 400 "run$run.launch.err")"
  fi
done
seconds=$(( ($(date +%s%N) - start) / 1000000 ))
kill -0 "${load[2]}" 2>/dev/null || echo "FAIL the second trio stopped: $(tail -c 300 second.err)"
echo "$passed/$runs runs kept the configuration of every episode ($episodes episodes), under two busy loops" \
  "and a second trio; $(awk -v s="$seconds" -v r="$runs" 'BEGIN { printf "%.1f", s / 1000 / r }') s per run;" \
  "launch restored a configuration lcm-logger lost in $restored run(s)"
[ "$passed" -eq "$runs" ] || { echo "FAIL $((runs - passed)) of $runs runs lost a configuration or failed"; exit 1; }
echo "ok   every run's log holds every episode's configuration"
