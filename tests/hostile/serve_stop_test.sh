#!/usr/bin/env bash
# `pidlab serve` stops clean after WebSocket sessions (docs/workbench.md,
# "Safe to leave running"), in a private network namespace of its own: two
# WebSockets are open (one has asked for the fields, one has said nothing)
# and a plain HTTP connection waits for its header when SIGTERM arrives; the
# server must exit 0 within 5 s with nothing on stderr but its "stopped"
# line. On a sanitised tree (BIN_DIR of build-asan) LeakSanitizer runs at
# exit: a session left holding the server is a leak report and exit 1.
#   serve_stop_test.sh BIN_DIR
set -uo pipefail
bin=$(realpath -- "${1:?usage: serve_stop_test.sh BIN_DIR}")
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
ip link set lo up || { echo "FAIL: cannot bring up the private namespace's loopback"; exit 1; }
here=$(cd "$(dirname -- "$0")" && pwd)
tmp=$(mktemp -d); trap 'kill $server $client 2>/dev/null; rm -rf "$tmp"' EXIT
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
"$bin/pidlab" serve --port 0 > "$tmp/out" 2> "$tmp/err" &
server=$! client=
for _ in $(seq 400); do grep -q '^pidlab serve: http' "$tmp/out" && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://127\.0\.0\.1:([0-9]+)/$#\1#p' "$tmp/out")
[ -n "$port" ] || { echo "FAIL: the server did not start: $(head -c 300 "$tmp/out" "$tmp/err")"; exit 1; }
/usr/bin/python3 - "$port" "$here/../cli" > "$tmp/client" 2>&1 <<'PY' &
import socket, sys, time
sys.path.insert(0, sys.argv[2])
from serve_client import WebSocket
port = int(sys.argv[1])
asked = WebSocket(port)
print('fields' if asked.ask({'id': 1, 'type': 'fields'}).get('type') == 'fields' else 'no fields', flush=True)
quiet = WebSocket(port)
waiting = socket.create_connection(('127.0.0.1', port))
waiting.sendall(b'GET / HTTP/1.1\r\nHo')
print('open', flush=True)
time.sleep(30)
PY
client=$!
for _ in $(seq 200); do grep -q '^open' "$tmp/client" && break; sleep 0.05; done
grep -q '^fields' "$tmp/client" || { echo "FAIL: the WebSocket session did not start: $(head -c 300 "$tmp/client")"; exit 1; }
start=$(date +%s%N)
kill -TERM "$server"
for _ in $(seq 100); do kill -0 "$server" 2>/dev/null || break; sleep 0.05; done
if kill -0 "$server" 2>/dev/null; then
  echo "FAIL: the server did not stop within 5 s of SIGTERM"; kill -KILL "$server"; exit 1
fi
wait "$server"; status=$?
ms=$((($(date +%s%N) - start) / 1000000))
others=$(grep -cv '^pidlab serve: stopped$' "$tmp/err")
if [ "$status" -eq 0 ] && [ "$others" -eq 0 ]; then
  echo "ok   the server stopped with status 0 in $ms ms after two WebSockets and a waiting connection"
else
  echo "FAIL: the server exited $status in $ms ms, $others other lines on stderr: $(grep -v '^pidlab serve: stopped$' "$tmp/err" | head -c 600)"
fi
