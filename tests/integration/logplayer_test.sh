#!/usr/bin/env bash
# lcm-logplayer round trip: a log written by `pidlab launch --log` (2 s at
# dt = 1 ms), played back by lcm-logplayer into a network namespace where only
# pidlab-controller runs (plus lcm-logger on the CONTROL lane), must drive the
# controller to the same commands: every step's u bit for bit (logplayer_check).
# The commands are the ones of docs/logs.md, "Driving a controller from a log
# with lcm-logplayer".
# Run as: unshare -n bash logplayer_test.sh BIN_DIR   (ctest does this)
set -uo pipefail

bin=$(realpath -- "${1:?usage: logplayer_test.sh BIN_DIR}")
export PATH=$bin:$PATH

# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
private_network_up

work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
cd "$work"

# ---- the live episode, logged (in a namespace of its own: --isolated) ----
# At its real pace (--realtime: 1 ms per step), as a real loop's log would
# be: the played stream is then slow enough for the recording lcm-logger,
# which drops beyond 30 queued messages (docs/logs.md, "Bursts").
if ! pidlab launch --isolated --realtime 1 --log run.lcmlog -- \
    pidlab evaluate --backend lcm --plant oscillator --gains 2,1,1.5 --loop sampled --dt 0.001 --horizon 2 \
    >live.txt 2>launch.err; then
  echo "FAIL launch failed: $(grep -v '^pidlab-' launch.err | tail -3)"
  exit 1
fi
if ! pidlab replay run.lcmlog >replay.txt 2>&1 || grep -q INCOMPLETE replay.txt; then
  echo "FAIL launch handed over an incomplete log: $(head -5 replay.txt)"
  exit 1
fi
echo "PASS launch --log wrote a complete log"

# ---- playback: only pidlab-controller, in this (empty) namespace ----
url=udpm://239.255.76.67:7667
lane1=udpm://239.255.76.67:7668   # PLANT_OUTPUT
lane2=udpm://239.255.76.67:7669   # CONTROL
# Both players pace from their own start. The controller answers a y only
# after the episode's configuration, and it has no deadline of its own, so
# the outputs' player starts only once the controller has taken the
# configuration (started together, a player delayed by the machine's load
# once let 1807 of 2000 y pass before the configuration arrived). A playback
# ends when the recording holds every step (logplayer_check), or after a
# deadline with steps missing (see below).
playback() {  # playback OUT.lcmlog: one playback into a fresh controller
  local out=$1 logger ctl a b
  lcm-logger -q -f "--lcm-url=$lane2?recv_buf_size=4194304" "$out" & logger=$!; pids+=($logger)
  pidlab-controller -v --lcm-url "$url?recv_buf_size=4194304" 2>controller.err & ctl=$!; pids+=($ctl)
  wait_until 10 log_has controller.err "serving on" ||
    { echo "FAIL pidlab-controller did not start: $(tail -2 controller.err)"; exit 1; }
  wait_until 10 test -e "$out" || { echo "FAIL lcm-logger did not open $out"; exit 1; }
  lcm-logplayer -s 0.5 -e '^PIDLAB_EPISODE_CONFIG$' -l "$url" run.lcmlog 2>>players.err & a=$!
  wait_until 10 log_has controller.err "episode [0-9]+: started" ||
    { echo "FAIL pidlab-controller never took the played-back configuration: $(tail -2 controller.err)"; exit 1; }
  lcm-logplayer -s 0.5 -e '^PIDLAB_PLANT_OUTPUT$' -l "$lane1" run.lcmlog 2>>players.err & b=$!
  wait "$a" "$b"
  wait_until 5 logplayer_check run.lcmlog "${recordings[@]}" "$out" >/dev/null
  kill -INT "$logger"; wait "$logger" 2>/dev/null
  kill "$ctl" 2>/dev/null; wait "$ctl" 2>/dev/null
}

# lcm-logplayer has no lockstep and no resends, and the lcm-logger recording
# CONTROL drops what it cannot queue (30 messages) when the machine starves
# it: on a loaded machine a step's answer can be missing from control.N.lcmlog
# though the controller answered it (seen with 4 CPU hogs on 2 cores: 0-10 of
# 2000, never a different u, the controller's own count 2000). A playback
# with steps missing but none different is played again into a fresh
# controller, up to 3 times, and said so with the controller's count; the
# recordings are checked together (a controller answers in step order, so a
# step recorded in any of them was reached, and every copy must agree bit for
# bit). Any different u fails at once.
recordings=()
for attempt in 1 2 3; do
  playback "control.$attempt.lcmlog"
  recordings+=("control.$attempt.lcmlog")
  if out=$(logplayer_check run.lcmlog "${recordings[@]}"); then
    echo "PASS the played-back log drove pidlab-controller to the same commands (playback $attempt): $out"
    exit 0
  fi
  if [[ $out != *"0 disagreeing); missing"*"different u 0, not in the original 0"* ]]; then
    echo "FAIL the controller's commands differ from the log's: $out"
    tail -5 controller.err
    exit 1
  fi
  echo "NOTE playback $attempt left steps unanswered, no u different: $out; $(grep -h 'done,\|received' controller.err | tr '\n' ' ')"
done
echo "FAIL three playbacks left steps unanswered: $out"
exit 1
