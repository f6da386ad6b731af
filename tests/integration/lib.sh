# Shared by the shell tests that run LCM processes. Source it:
#   . "$(dirname "$0")/../integration/lib.sh"
#
# private_network_up: the prelude of every such test. ctest runs the test as
# `unshare -n bash TEST.sh ...`; this refuses to go on unless the shell is in
# a private network namespace holding nothing but a loopback (the namespace
# of pid 1 may be unreadable: the interfaces decide then), and routes
# multicast over that loopback, so nothing is ever sent outside:
#   ip link set lo up; ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo
# On failure it prints one "FAIL ..." line and exits 1.
private_network_up() {
  if [ "$(readlink /proc/self/ns/net)" = "$(readlink /proc/1/ns/net 2>/dev/null)" ] ||
     [ "$(ip -o link show | wc -l)" -ne 1 ]; then
    echo "FAIL not in a private network namespace holding only lo (run under unshare -n)"
    exit 1
  fi
  ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo || {
    echo "FAIL cannot route multicast over the namespace's loopback"
    exit 1
  }
}

# wait_until SECONDS COMMAND [ARGS...]: runs COMMAND every 20 ms until it
# succeeds (returns 0) or SECONDS have passed (returns 1). A wait on
# readiness (a file, a log line, a process) with a deadline, never a guess
# at how long something takes.
wait_until() {
  local deadline=$(( $(date +%s%N) + ${1%.*} * 1000000000 ))
  shift
  until "$@"; do
    [ "$(date +%s%N)" -lt "$deadline" ] || return 1
    sleep 0.02
  done
}

# log_has FILE PATTERN: FILE exists and a line matches PATTERN (grep -E).
log_has() { [ -f "$1" ] && grep -Eq -- "$2" "$1"; }

# file_bigger_than FILE BYTES: FILE exists and holds more than BYTES bytes.
file_bigger_than() { [ -f "$1" ] && [ "$(stat -c %s "$1")" -gt "$2" ]; }

# wakeups PID: how many times PID has blocked and woken again so far
# (voluntary context switches). A role idles with a wake-up every 50 ms;
# serving an episode it wakes for every message, thousands a second, so
#   base=$(wakeups $PID); ...; wait_until 30 woke_since $PID $base 1000
# waits until PID has handled an episode's first thousand or so messages.
wakeups() { awk '/^voluntary_ctxt_switches/ {print $2}' "/proc/$1/status" 2>/dev/null || echo 0; }
woke_since() { [ "$(wakeups "$1")" -gt $(( $2 + $3 )) ]; }
