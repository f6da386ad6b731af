#!/usr/bin/env bash
# Roles spread over hosts: a four-host LAN built out of network
# namespaces, inside a private network and mount namespace of this test's own
# (it re-executes itself under `unshare -n -m --propagation private`; root is
# needed), so nothing it sends can leave the machine and `ip netns add` stays
# private (a tmpfs on /run/netns).
#
#   br0 (bridge, mcast_snooping 0)
#    |-- veth1 == eth0 of h1  10.77.0.1/24
#    |-- veth2 == eth0 of h2  10.77.0.2/24
#    |-- veth3 == eth0 of h3  10.77.0.3/24
#    `-- veth4 == eth0 of h4  10.77.0.4/24
#
# Each host has lo up and `ip route add 224.0.0.0/4 dev eth0`; LCM runs with
# ttl=1 (the default ttl=0 never leaves a host).
#   one:  a trio on port 7667: `pidlab launch --roles plant` on h1, `--roles
#         controller` on h2, `--roles disturbance` on h3 (serving); h4 runs
#         `pidlab evaluate --backend lcm` for the double integrator and for
#         the stepper motor.
#   two:  two trios at once: A on port 7667 (plant h1, controller h2,
#         disturbance h3), B on port 7677 (plant h2, controller h3,
#         disturbance h1); h4 runs a client on each concurrently, twice
#         (each trio gets each plant).
# Every client's JSON, without "backend" and "steps_per_second", must equal
# the in-process `pidlab evaluate --loop sampled --json` byte for byte. Every
# launcher must exit 0 after SIGINT, and no process may be left in a host.
# The test never depends on which ports of the group a trio uses beyond its
# base port (trio B's is 10 above A's): nothing is firewalled.
# usage: lan_test.sh BIN_DIR     (prints PASS .../FAIL ... lines)
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"  # wait_until, log_has
if [ $# -ne 1 ]; then
  echo "usage: $0 BIN_DIR" >&2
  exit 2
fi
if [ "${PIDLAB_LAN_PRIVATE:-}" != 1 ]; then
  if ! unshare -n -m --propagation private true 2>/dev/null; then
    echo "FAIL lan: cannot create a private network and mount namespace (unshare -n -m: root is needed)"
    exit 1
  fi
  PIDLAB_LAN_PRIVATE=1 exec unshare -n -m --propagation private bash "$0" "$@"
fi
if [ "$(readlink /proc/self/ns/net)" = "$(readlink /proc/1/ns/net)" ] ||
  [ "$(readlink /proc/self/ns/mnt)" = "$(readlink /proc/1/ns/mnt)" ]; then
  echo "FAIL lan: refusing to run outside a private network and mount namespace"
  exit 1
fi

BIN=$(cd "$1" && pwd) || { echo "FAIL lan: no directory $1"; exit 1; }
PIDLAB=$BIN/pidlab
[ -x "$PIDLAB" ] || { echo "FAIL lan: $PIDLAB is not an executable"; exit 1; }
TMP=$(mktemp -d)
HOSTS="h1 h2 h3 h4"
T0=$(date +%s%N)
fail=0
declare -A PID=()  # NAME -> pid of a running launcher (ip netns exec and setpriv exec pidlab)

cleanup() {
  local h pid
  for pid in "${PID[@]}"; do kill -KILL "$pid" 2>/dev/null; done
  for h in $HOSTS; do
    for pid in $(ip netns pids "$h" 2>/dev/null); do kill -KILL "$pid" 2>/dev/null; done
    ip netns del "$h" 2>/dev/null
  done
  rm -rf "$TMP"
}
trap cleanup EXIT
trap 'echo "FAIL lan: interrupted"; exit 1' INT TERM

die() { echo "FAIL lan: $*"; exit 1; }
elapsed() { echo $((($(date +%s%N) - T0) / 1000000)); }

# ---- The LAN
# A tmpfs on /run/netns, in this mount namespace only, so that `ip netns add`
# stays private (if the folder does not exist, a tmpfs on /run holds it: the
# host's /run is not touched either way).
# (mount -n: no utab entry in the host's /run/mount either.)
if [ -d /run/netns ]; then
  mount -n -t tmpfs -o size=1m,mode=755 pidlab-lan /run/netns || die "cannot mount a tmpfs on /run/netns"
else
  mount -n -t tmpfs -o size=1m,mode=755 pidlab-lan /run && mkdir /run/netns || die "cannot mount a tmpfs on /run"
fi
mountpoint -q /run/netns || [ "$(stat -f -c %T /run/netns)" = tmpfs ] || die "/run/netns is not on a private tmpfs"
ip link set lo up || die "lo"
ip link add br0 type bridge mcast_snooping 0 && ip link set br0 up || die "cannot create the bridge br0"
ip -d link show br0 | grep -q 'mcast_snooping 0' || die "br0 snoops IGMP: $(ip -d link show br0 | tail -1)"
i=0
for h in $HOSTS; do
  i=$((i + 1))
  ip netns add "$h" &&
    ip link add "veth$i" type veth peer name eth0 netns "$h" &&
    ip link set "veth$i" master br0 up &&
    ip -n "$h" link set lo up &&
    ip -n "$h" addr add "10.77.0.$i/24" dev eth0 &&
    ip -n "$h" link set eth0 up &&
    ip -n "$h" route add 224.0.0.0/4 dev eth0 || die "cannot set up host $h"
done
# Every eth0 is up (both ends of its veth are; no carrier delay on veth).
eth0_up() { ip -n "$1" link show eth0 | grep -q "state UP"; }
for h in $HOSTS; do
  wait_until 5 eth0_up "$h" || die "eth0 of $h is not up: $(ip -n "$h" link show eth0)"
done
echo "ok   lan: 4 hosts 10.77.0.1-4 on br0 (mcast_snooping 0), 224.0.0.0/4 via eth0 on each, in $(elapsed) ms"

url() { echo "udpm://239.255.76.67:$1?ttl=1&recv_buf_size=4194304"; }

# launch NAME HOST ROLE PORT: `pidlab launch --roles ROLE` serving on HOST.
launch() {
  local name=$1 host=$2 role=$3 port=$4
  # setpriv: killed if this script is (a ctest timeout), and its roles with it.
  ip netns exec "$host" setpriv --pdeathsig KILL "$PIDLAB" launch --roles "$role" --lcm-url "$(url "$port")" \
    >"$TMP/$name.out" 2>"$TMP/$name.err" &
  PID[$name]=$!
}

# wait_ready NAME...: each launcher said "ROLE ready on URL" within 15 s.
ready_or_gone() { log_has "$1" " ready on udpm://" || ! kill -0 "$2" 2>/dev/null; }
wait_ready() {
  local name pid
  for name in "$@"; do
    pid=${PID[$name]}
    wait_until 15 ready_or_gone "$TMP/$name.err" "$pid"
    grep -q " ready on udpm://" "$TMP/$name.err" ||
      die "$name did not get ready: $(head -c 300 "$TMP/$name.err")"
  done
}

# stop NAME...: SIGINT to each launcher, which must exit 0 within 10 s.
gone() { ! kill -0 "$1" 2>/dev/null; }
stop() {
  local name pid rc
  for name in "$@"; do kill -INT "${PID[$name]}"; done
  for name in "$@"; do
    pid=${PID[$name]}
    wait_until 10 gone "$pid"
    if kill -0 "$pid" 2>/dev/null; then
      echo "FAIL $name: still running 10 s after SIGINT"; fail=1; kill -KILL "$pid"
    fi
    wait "$pid"; rc=$?
    unset "PID[$name]"  # reaped: its pid is no longer ours to kill
    if [ $rc -ne 0 ]; then
      echo "FAIL $name: exit $rc after SIGINT: $(head -c 300 "$TMP/$name.err")"; fail=1
    elif grep -q "killed by signal\|exited with status" "$TMP/$name.err"; then
      echo "FAIL $name: a process died: $(grep "killed by signal\|exited with status" "$TMP/$name.err" | head -2)"
      fail=1
    else
      echo "ok   $name: exit 0 after SIGINT"
    fi
  done
}

# No process is left in any host.
no_leftovers() {
  local h pids
  for h in $HOSTS; do
    pids=$(ip netns pids "$h" | tr '\n' ' ')
    [ -z "$pids" ] || { echo "FAIL $1: processes left in $h: $pids"; fail=1; }
  done
}

strip() { sed 's/"backend":"[a-z]*",//; s/,"steps_per_second":[^,}]*//' "$1"; }

DI=(--plant double_integrator --gains "2,1,1.5" --loop sampled --horizon 2 --disturbance square
  --disturbance-amplitude 0.2)
STEPPER=(--plant stepper_motor --gains "5,10,0.05" --loop sampled --dt 1e-4 --sample-time 0.05 --horizon 0.5
  --disturbance square --disturbance-amplitude 0.2 --disturbance-period 0.2)
"$PIDLAB" evaluate "${DI[@]}" --json >"$TMP/di.ref.raw" && strip "$TMP/di.ref.raw" >"$TMP/di.ref" ||
  die "in-process evaluate (double integrator) failed"
"$PIDLAB" evaluate "${STEPPER[@]}" --json >"$TMP/stepper.ref.raw" && strip "$TMP/stepper.ref.raw" >"$TMP/stepper.ref" ||
  die "in-process evaluate (stepper) failed"
for p in di stepper; do
  jq -e '.stable == true and .iae != null and .backend == "local"' "$TMP/$p.ref.raw" >/dev/null ||
    die "the in-process $p loop is not stable: nothing to compare"
done

# client NAME PORT PLANT: `pidlab evaluate --backend lcm` on h4 (PLANT: di |
# stepper); its exit code and JSON are checked by compare NAME PLANT.
client() {
  local name=$1 port=$2 plant=$3 args
  if [ "$plant" = di ]; then args=("${DI[@]}"); else args=("${STEPPER[@]}"); fi
  timeout 60 ip netns exec h4 "$PIDLAB" evaluate --backend lcm --lcm-url "$(url "$port")" "${args[@]}" --json \
    >"$TMP/$name.raw" 2>"$TMP/$name.cerr"
  echo $? >"$TMP/$name.rc"
}
compare() {
  local name=$1 plant=$2 rc
  rc=$(cat "$TMP/$name.rc")
  if [ "$rc" -ne 0 ]; then
    echo "FAIL $name: the client on h4 exited $rc: $(tail -n 1 "$TMP/$name.cerr" | head -c 300)"; fail=1
  elif ! jq -e '.backend == "lcm"' "$TMP/$name.raw" >/dev/null; then
    echo "FAIL $name: not an lcm result: $(head -c 200 "$TMP/$name.raw")"; fail=1
  elif ! strip "$TMP/$name.raw" | cmp -s - "$TMP/$plant.ref"; then
    echo "FAIL $name: the JSON differs from the in-process loop"
    diff <(strip "$TMP/$name.raw" | jq -S .) <(jq -S . "$TMP/$plant.ref") | head -6
    fail=1
  else
    echo "PASS $name: iae $(jq -r .iae "$TMP/$name.raw") bit-identical to the in-process loop" \
      "($(jq '.steps_per_second | floor' "$TMP/$name.raw") steps/s)"
  fi
}

# tx_packets HOST: datagrams sent on the host's eth0 so far.
tx_packets() { ip -n "$1" -s -j link show eth0 | jq '.[0].stats64.tx.packets'; }

# ---- One: a trio over h1..h3, the client on h4
declare -A TX0
for h in $HOSTS; do TX0[$h]=$(tx_packets "$h"); done
launch one_plant h1 plant 7667
launch one_controller h2 controller 7667
launch one_disturbance h3 disturbance 7667
wait_ready one_plant one_controller one_disturbance
echo "ok   one: plant on h1, controller on h2, disturbance on h3 ready on $(url 7667) at $(elapsed) ms"
client one_di 7667 di
compare one_di di
client one_stepper 7667 stepper
compare one_stepper stepper
for h in $HOSTS; do
  sent=$(($(tx_packets "$h") - TX0[$h]))
  # h1 and h2 (plant, controller) send every step, h3 a block of the
  # disturbance every 128 steps, h4 the configurations and requests.
  if [ "$sent" -lt 10 ]; then
    echo "FAIL one: $h sent only $sent datagrams over the LAN"; fail=1
  else
    echo "ok   one: $h sent $sent datagrams over the LAN"
  fi
done
stop one_plant one_controller one_disturbance
no_leftovers one

# ---- Two: two trios over h1..h3 at once, both clients on h4 concurrently
launch a_plant h1 plant 7667
launch a_controller h2 controller 7667
launch a_disturbance h3 disturbance 7667
launch b_plant h2 plant 7677
launch b_controller h3 controller 7677
launch b_disturbance h1 disturbance 7677
wait_ready a_plant a_controller a_disturbance b_plant b_controller b_disturbance
echo "ok   two: trio A (h1 plant, h2 controller, h3 disturbance) on port 7667 and trio B (h2, h3, h1)" \
  "on port 7677 ready at $(elapsed) ms"
for round in 1 2; do
  if [ $round -eq 1 ]; then pa=di pb=stepper; else pa=stepper pb=di; fi
  client "two_a${round}_$pa" 7667 "$pa" & ca=$!
  client "two_b${round}_$pb" 7677 "$pb" & cb=$!
  wait $ca $cb
  compare "two_a${round}_$pa" "$pa"
  compare "two_b${round}_$pb" "$pb"
done
stop a_plant a_controller a_disturbance b_plant b_controller b_disturbance
no_leftovers two

if [ $fail -eq 0 ]; then
  echo "PASS lan: 6 evaluations over 4 hosts bit-identical to the in-process loop, in $(elapsed) ms"
else
  echo "FAIL lan (in $(elapsed) ms)"
fi
exit $fail
