#!/usr/bin/env bash
# integration.launch_log_restores_a_configuration_its_logger_lost: an episode
# whose every configuration copy lcm-logger lost still has its configuration
# in `pidlab launch --log`'s log. COMMAND stops the base logger (SIGSTOP),
# fills its socket (lcm_flood.py: the kernel then drops every datagram for
# it), runs one `pidlab evaluate --backend lcm` and lets the logger go on.
# launch must say that lcm-logger lost that episode's configuration and that
# the log got launch's own copy, exit 0, and `pidlab replay --json` must find
# the episode complete with its configuration, once without a key and once
# with --auth-key (the copy carries the client's tag).
# Run as: unshare -n bash log_config_test.sh BIN_DIR   (ctest does this)
set -uo pipefail
bin=$(realpath -- "${1:?usage: log_config_test.sh BIN_DIR}")
pidlab=$bin/pidlab
here=$(dirname "$(realpath -- "${BASH_SOURCE[0]}")")

# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$here/lib.sh"
private_network_up
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
cd "$work" || exit 1
url="udpm://239.255.76.67:7667?ttl=0"
head -c 32 /dev/urandom >trio.key
fail=0

for mode in plain keyed; do
  key=()
  [ "$mode" = keyed ] && key=(--auth-key trio.key)
  "$pidlab" launch --lcm-url "$url" --log "$mode.lcmlog" "${key[@]}" -- bash -c '
    kill -STOP "$PIDLAB_LOGGER_PID" || exit 3
    python3 "$1" 239.255.76.67 7667 30000 >&2 || exit 3
    # The kernel has dropped datagrams for the stopped logger: its socket is full.
    pidlab evaluate --backend lcm -v --plant double_integrator --gains 2,1,1.5 --horizon 2 \
      --json >"$2.json" 2>"$2.err"
    rc=$?
    kill -CONT "$PIDLAB_LOGGER_PID"
    exit $rc' launch "$here/lcm_flood.py" "$mode" >"$mode.launch.out" 2>"$mode.launch.err"
  rc=$?
  id=$(sed -n 's/^pidlab: note: episode \([0-9]*\) ran$/\1/p' "$mode.err" | head -n 1)
  if [ "$rc" -ne 0 ] || [ -z "$id" ]; then
    echo "FAIL $mode: launch exited $rc (episode '${id}'): $(tail -c 600 "$mode.launch.err") $(tail -c 300 "$mode.err" 2>/dev/null)"
    fail=1
    continue
  fi
  if grep -q "lcm-logger lost the configuration of episode $id; $mode.lcmlog gets launch's own copy" \
    "$mode.launch.err"; then
    echo "ok   $mode: launch restored the configuration of episode $id: $(grep -o 'lcm-logger lost the configuration.*' "$mode.launch.err")"
  else
    echo "FAIL $mode: launch did not say it restored episode $id's configuration: $(tail -c 600 "$mode.launch.err")"
    fail=1
  fi
  replay_key=()
  [ "$mode" = keyed ] && replay_key=(--auth-key trio.key)
  "$pidlab" replay "$mode.lcmlog" --json "${replay_key[@]}" >"$mode.replay.json" 2>"$mode.replay.err"
  verdict=$(python3 - "$mode.replay.json" "$id" "$mode.json" <<'PY'
import json, sys
log = json.load(open(sys.argv[1]))
episode = [e for e in log["episodes"] if e["episode_id"] == int(sys.argv[2])]
live = json.load(open(sys.argv[3]))
if not episode:
    print("no episode %s in the log" % sys.argv[2])
elif "config" not in episode[0]:
    print("episode %s has no configuration in the log: %s" % (sys.argv[2], episode[0].get("completeness")))
elif not episode[0]["complete"]:
    print("episode %s is incomplete: %s" % (sys.argv[2], episode[0]["completeness"]))
elif episode[0]["evaluation"]["iae"] != live["iae"]:
    print("the log's IAE %r is not the live %r" % (episode[0]["evaluation"]["iae"], live["iae"]))
elif log["unauthenticated_events"]:
    print("%d unauthenticated events" % log["unauthenticated_events"])
else:
    print("ok")
PY
)
  if [ "$verdict" = ok ]; then
    echo "ok   $mode: pidlab replay finds episode $id complete, with its configuration and the live IAE"
  else
    echo "FAIL $mode: $verdict"
    fail=1
  fi
done
exit $fail
