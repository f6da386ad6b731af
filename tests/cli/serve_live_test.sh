#!/usr/bin/env bash
# pidlab serve --lcm-url (docs/live.md), in a private network namespace of its
# own: with a trio started by `pidlab launch`, a WebSocket client subscribes
# to the live scope while `pidlab evaluate --backend lcm` runs an episode; the
# final kind-2 frame equals the episode's trajectory bit for bit, the status
# shows it complete, live_data answers the same, run_on_trio agrees with the
# prediction bit for bit; without --lcm-url the live requests answer 400 and
# --auth-key or --channel-prefix exit 2 with one line; the commands of
# docs/live.md run.
set -uo pipefail
if [[ $# -ne 1 ]]; then
  echo "usage: $0 PIDLAB_BINARY" >&2
  exit 2
fi
pidlab=$(realpath -- "$1")
here=$(cd "$(dirname -- "$0")" && pwd)
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo || {
  echo "FAIL: cannot route multicast over the private namespace's loopback"
  exit 1
}
source "$here/stderr_shape.sh"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

"$pidlab" serve --help > help
check "serve --help names --lcm-url, --channel-prefix and --auth-key" \
  "grep -q -- '--lcm-url' help && grep -q -- '--channel-prefix' help && grep -q -- '--auth-key' help"
head -c 32 /dev/urandom > key
for case in "--auth-key key|--auth-key 'key' needs --lcm-url" "--channel-prefix X_|--channel-prefix 'X_' needs --lcm-url"; do
  args=${case%%|*} needle=${case#*|}
  timeout 10 "$pidlab" serve --port 0 $args > out 2> err
  check "serve $args without --lcm-url exits 2 with one line" "[ $? -eq 2 ] && only_line_ok err \"$needle\" && [ ! -s out ]"
done

# Starts `pidlab serve ARGS` and waits (10 s at most) for its URL line; sets server and port.
start() {
  "$pidlab" serve --port 0 "$@" > serve.out 2> serve.err &
  server=$!
  for _ in $(seq 200); do grep -q '^pidlab serve: http' serve.out && break; sleep 0.05; done
  port=$(sed -nE 's#^pidlab serve: http://[^/]*:([0-9]+)/.*#\1#p' serve.out | head -1)
}

start
PYTHONPATH="$here" /usr/bin/python3 - "$port" > plain.out <<'PY'
import sys
from serve_client import WebSocket
ws = WebSocket(int(sys.argv[1]))
print(ws.ask({'type': 'server_info'}))
print(ws.ask({'type': 'live_subscribe'}))
PY
check "without --lcm-url server_info says live false" "grep -q \"'live': False\" plain.out"
check "without --lcm-url live_subscribe answers the contract's error" \
  "grep -q 'live: pidlab serve was started without --lcm-url' plain.out"
kill -TERM "$server"; wait "$server"
check "SIGTERM stops the server with status 0" "[ $? -eq 0 ]"

# The live scope on a trio: `pidlab launch` runs this script's second half.
cat > inner.sh <<'INNER'
set -u
pidlab=$1 here=$2
"$pidlab" serve --port 0 --lcm-url "$PIDLAB_LCM_URL" > serve.out 2> serve.err &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' serve.out && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://[^/]*:([0-9]+)/.*#\1#p' serve.out | head -1)
PYTHONPATH="$here" /usr/bin/python3 "$here/serve_live_client.py" "$port" "$pidlab" "$PWD"
status=$?
kill -TERM "$server"; wait "$server" || status=1
exit $status
INNER
timeout 240 "$pidlab" launch --quiet -- bash inner.sh "$pidlab" "$here" > live.out 2> live.err
status=$?
cat live.out
check "the live scope's checks pass over a launched trio (exit $status)" "[ $status -eq 0 ] && ! grep -q '^FAIL' live.out"
[ $status -eq 0 ] || { echo "--- stderr"; tail -n 20 live.err; tail -n 5 serve.err 2>/dev/null; }

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
