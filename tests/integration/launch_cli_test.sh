#!/usr/bin/env bash
# pidlab launch: every documented form of the command line parses (the
# --realtime forms among them), an unknown subcommand is named, a process
# killed in any trio of --trios K is reported with its trio's number and
# reaped at once, and a log on a full disk stops the run with one line that
# names the cause, the file, the episode and steps the log misses, and the
# lane files it keeps.
# The whole test runs in a private network and mount namespace of its own.
# Usage: launch_cli_test.sh PIDLAB_BINARY
set -uo pipefail

if [[ $# -ne 1 ]]; then
  echo "usage: $0 PIDLAB_BINARY" >&2
  exit 2
fi
pidlab=$(realpath -- "$1")
[[ -x $pidlab ]] || { echo "FAIL: $pidlab is not an executable" >&2; exit 1; }
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n -m --propagation private bash "$0" "$@"
fi
ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo || {
  echo "FAIL: cannot route multicast over the private namespace's loopback"
  exit 1
}
source "$(dirname -- "$0")/../cli/stderr_shape.sh"
export PATH="$(dirname -- "$pidlab"):$PATH"

work=$(mktemp -d)
trap 'umount "$work/small" 2>/dev/null; rm -rf "$work"' EXIT
cd "$work" || exit 1

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

evaluate=(pidlab evaluate --backend lcm --plant oscillator --gains 2,1,1.5 --loop sampled --horizon 0.3 --json)

# Each documented form of launch with a COMMAND: exit 0 and COMMAND's JSON on
# stdout; the --realtime forms pace the plant at the factor given.
form() {
  local what=$1 paced=$2
  shift 2
  local status=0
  timeout 60 "$pidlab" launch "$@" -- "${evaluate[@]}" >form.out 2>form.err || status=$?
  if ((status != 0)); then
    fail "launch $what: exit $status: $(tail -n 1 form.err)"
  elif ! grep -q '"iae"' form.out; then
    fail "launch $what: no evaluation on stdout"
  elif [[ -n $paced ]] && ! grep -q "paced ${paced}x" form.err; then
    fail "launch $what: the plant did not report 'paced ${paced}x'"
  else
    pass "launch $what -- COMMAND"
  fi
}
form "" ""
form "--isolated" "" --isolated
form "--realtime" 1 --realtime
form "--realtime 1" 1 --realtime 1
form "--realtime 2" 2 --realtime 2
form "--realtime=2" 2 --realtime=2
form "--isolated --realtime 1 --log run.lcmlog" 1 --isolated --realtime 1 --log run.lcmlog
form "--realtime --verbose" 1 --realtime --verbose
form "--log run.lcmlog" "" --log run.lcmlog
form "--trios 2" "" --trios 2
form "--drop-rate 0.05" "" --drop-rate 0.05
form "--roles plant,controller,disturbance" "" --roles plant,controller,disturbance

status=0
"$pidlab" frobnicate --x 1 >unknown.out 2>unknown.err || status=$?
if ((status != 2)); then
  fail "an unknown subcommand exits $status (wanted 2)"
elif ! why=$(only_line_ok unknown.err "'frobnicate' is not a subcommand"); then
  fail "an unknown subcommand: $why"
else
  pass "an unknown subcommand is named in one line, exit 2"
fi

# kill_in_trio I K: COMMAND kills trio I's plant and waits (1 s at most) until
# launch has reaped it; launch must note it with the trio's number.
kill_in_trio() {
  local i=$1 k=$2 status=0
  timeout 30 "$pidlab" launch --trios "$k" -- bash -c '
    pid_var=PIDLAB_TRIO'"$i"'_PLANT_PID
    pid=${!pid_var}
    kill -9 "$pid"
    deadline=$(($(date +%s%N) + 1000000000))
    while [[ -e /proc/$pid ]]; do  # a zombie keeps its /proc entry
      (($(date +%s%N) < deadline)) || { echo "pid $pid not reaped within 1 s" >&2; exit 1; }
      sleep 0.01
    done' >kill.out 2>kill.err || status=$?
  local note="trio $i: pidlab-plant (pid "
  ((k == 1)) && note="pidlab-plant (pid "
  if ((status != 0)); then
    fail "kill in trio $i of $k: exit $status: $(tr '\n' '|' <kill.err)"
  elif ! grep -q "^pidlab launch: ${note}[0-9]*) killed by signal Killed" kill.err; then
    fail "kill in trio $i of $k: no note '${note}...) killed by signal Killed': $(tr '\n' '|' <kill.err)"
  else
    pass "a kill in trio $i of $k is reaped within 1 s and noted with its trio's number"
  fi
}
kill_in_trio 2 2
kill_in_trio 1 2
kill_in_trio 3 3

# A stopped process is noted as it happens, with its trio's number. COMMAND
# waits until its process state shows the stop (T), keeps it stopped for
# 0.5 s (a stop continued before the supervisor's next waitpid is no longer
# there to see: continued at once, it was missed under load), then continues it.
status=0
timeout 30 "$pidlab" launch --trios 2 -- bash -c '
  pid=$PIDLAB_TRIO2_CONTROLLER_PID
  kill -STOP "$pid"
  deadline=$(($(date +%s%N) + 1000000000))
  until [[ $(ps -o stat= -p "$pid") == T* ]]; do
    (($(date +%s%N) < deadline)) || exit 1
    sleep 0.01
  done
  sleep 0.5
  kill -CONT "$pid"' >stop.out 2>stop.err || status=$?
if ((status != 0)); then
  fail "a stop in trio 2: exit $status: $(tr '\n' '|' <stop.err)"
elif ! grep -q "^pidlab launch: trio 2: pidlab-controller (pid [0-9]*) stopped by signal" stop.err; then
  fail "a stop in trio 2 is not noted: $(tr '\n' '|' <stop.err)"
else
  pass "a stop in trio 2 of 2 is noted with its trio's number"
fi

# A full disk: a 64 KiB tmpfs fills within the first second of a 25 s
# evaluation. Launch must stop COMMAND within 1 s of the loggers' death
# (measured from the last write into the log files) and end with one line
# naming the cause and a file, keeping the lane files.
mkdir small && mount -t tmpfs -o size=64k tmpfs small || { echo "FAIL: cannot mount a tmpfs"; exit 1; }
status=0
timeout 60 "$pidlab" launch --log small/run.lcmlog -- pidlab evaluate --backend lcm --plant oscillator \
  --gains 2,1,1.5 --loop sampled --horizon 25 --json >full.out 2>full.err || status=$?
ended=$(date +%s.%N)
last_write=$(stat -c %.9Y small/run.lcmlog* | sort -n | tail -n 1)
if ((status != 1)); then
  fail "disk full: exit $status (wanted 1): $(tr '\n' '|' <full.err)"
elif ! why=$(final_line_ok full.err "No space left on device"); then
  fail "disk full: $why"
elif ! tail -n 1 full.err | grep -q "small/run.lcmlog"; then
  fail "disk full: the line does not name the file: $(tail -n 1 full.err)"
elif [[ ! -s small/run.lcmlog.lane1 || ! -s small/run.lcmlog.lane2 ]]; then
  fail "disk full: the lane files were not kept: $(ls -l small | tr '\n' '|')"
elif ! tail -n 1 full.err | grep -q "kept small/run.lcmlog and its .lane1, .lane2$"; then
  fail "disk full: the kept files are not named: $(tail -n 1 full.err)"
elif ! awk -v a="$ended" -v b="$last_write" 'BEGIN { exit !(a - b < 1.5) }'; then
  fail "disk full: launch ended $(awk -v a="$ended" -v b="$last_write" 'BEGIN { print a - b }') s after the last write"
else
  pass "disk full: exit 1 within 1 s of the loggers' death, one line: $(tail -n 1 full.err)"
fi
# The line names the episode the log misses steps of and those steps, as
# pidlab replay reports them: the first episode with its configuration in the
# log that is incomplete (and did not fail live), the union of its three
# streams' missing steps (count and at most two ranges), how many more
# episodes miss steps.
"$pidlab" replay --json small/run.lcmlog >replay.json 2>replay.err || true
if ! why=$(/usr/bin/python3 - "$(tail -n 1 full.err)" 2>&1 <<'PY'
import json, sys
line = sys.argv[1]
try:
    log = json.load(open("replay.json"))
except ValueError as e:
    sys.exit("pidlab replay gave no JSON: %s" % e)
def missing(e):
    ranges = sorted(tuple(r) for s in ("plant_outputs", "commands", "disturbance_samples")
                    for r in e[s]["missing"])
    merged = []
    for a, b in ranges:
        if merged and a <= merged[-1][1] + 1:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    return merged
incomplete = [e for e in log["episodes"] if "plant" in e and not e["complete"]
              and e.get("summary", {}).get("status") != "failed"]
if not incomplete:
    sys.exit("pidlab replay finds no incomplete episode in small/run.lcmlog")
e = incomplete[0]
m = missing(e)
text = ",".join(str(a) if a == b else "%d-%d" % (a, b) for a, b in m[:2])
if len(m) > 2:
    text += ",... (%d ranges)" % len(m)
more = len(incomplete) - 1
want = "small/run.lcmlog misses %d steps of episode %d" % (sum(b - a + 1 for a, b in m), e["episode_id"])
if more:
    want += " (and of %d more episode%s)" % (more, "" if more == 1 else "s")
want += ": " + text + "; kept"
if want not in line:
    sys.exit("wanted '%s' in: %s" % (want, line))
print(want)
PY
); then
  fail "disk full: the episode and steps the log misses: $why"
else
  pass "disk full: the line names what pidlab replay finds missing: $why"
fi
if ! grep -q "KiB free beside small/run.lcmlog" full.err; then
  fail "disk full: launch did not say at the start that the disk is nearly full"
else
  pass "disk full: launch says at the start that the disk is nearly full"
fi

# --quiet: the same failure is the only line on stderr.
umount small && mount -t tmpfs -o size=64k tmpfs small || { echo "FAIL: cannot mount a tmpfs"; exit 1; }
status=0
timeout 60 "$pidlab" launch --quiet --log small/run.lcmlog -- pidlab evaluate --backend lcm --plant oscillator \
  --gains 2,1,1.5 --loop sampled --horizon 25 --json >full.out 2>full.err || status=$?
if ((status != 1)); then
  fail "disk full, --quiet: exit $status (wanted 1): $(tr '\n' '|' <full.err)"
elif ! why=$(only_line_ok full.err "No space left on device"); then
  fail "disk full, --quiet: $why"
else
  pass "disk full, --quiet: the failure is the only line"
fi

status=0
"$pidlab" launch --quiet --verbose -- true >qv.out 2>qv.err || status=$?
if ((status != 2)); then
  fail "--quiet --verbose exits $status (wanted 2)"
elif ! why=$(only_line_ok qv.err "--quiet and --verbose"); then
  fail "--quiet --verbose: $why"
else
  pass "--quiet --verbose is bad input, one line"
fi

echo "$passed passed, $failed failed"
((failed == 0))
