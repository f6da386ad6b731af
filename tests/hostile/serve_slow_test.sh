#!/usr/bin/env bash
# Slow clients and deep JSON against `pidlab serve` (docs/workbench.md, "Safe
# to leave running"), in a private network namespace of its own, on
# 127.0.0.1 only: 64 connections from 127.0.0.1 that each send one header
# byte every 2 s (reopened when closed), and 48 more from three other
# addresses that fill the global cap, must not keep /api/health and the page
# from answering a user at 127.0.0.2 within 1 s; nor may 64 WebSockets that
# never answer a ping and 64 POSTs trickling their bodies, 16 of each from
# every one of 127.0.1.1-4 (4 of 4 checks within 1 s); requests nested 30 000 and 100 000 deep, over HTTP
# and the WebSocket, are refused and the server keeps answering; SIGTERM
# stops it with status 0. Bounded: about 40 s.
#   serve_slow_test.sh PIDLAB_BINARY
set -uo pipefail
if [[ $# -ne 1 ]]; then
  echo "usage: $0 PIDLAB_BINARY" >&2
  exit 2
fi
pidlab=$(realpath -- "$1")
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
ip link set lo up || { echo "FAIL: cannot bring up the private namespace's loopback"; exit 1; }
here=$(cd "$(dirname -- "$0")" && pwd)
tmp=$(mktemp -d); trap 'kill $server 2>/dev/null; rm -rf "$tmp"' EXIT
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
"$pidlab" serve --port 0 > "$tmp/out" 2> "$tmp/err" &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' "$tmp/out" && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://127\.0\.0\.1:([0-9]+)/$#\1#p' "$tmp/out")
[ -n "$port" ] || { echo "FAIL: the server did not start on 127.0.0.1: $(head -c 300 "$tmp/out" "$tmp/err")"; exit 1; }
timeout 60 /usr/bin/python3 "$here/serve_slow.py" "$port" 64 8 ||
  echo "FAIL: slow clients or deep JSON found a failure (exit $?)"
if kill -0 "$server" 2>/dev/null; then
  kill -TERM "$server"; wait "$server"; status=$?
  [ "$status" -eq 0 ] && echo "ok   the server stopped with status 0" || echo "FAIL: the server exited $status"
else
  wait "$server"; echo "FAIL: the server died (status $?)"
fi
cat "$tmp/err"
