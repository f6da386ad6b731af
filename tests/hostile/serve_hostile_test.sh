#!/usr/bin/env bash
# Hostile input against `pidlab serve` (docs/workbench.md, "Safe to leave
# running"), in a private network namespace: COUNT seeded malformed HTTP
# requests and hostile WebSocket frames (half each: random bytes, mutated
# valid requests, huge targets, chunked garbage, bodies that are not specs or
# nest 60000 deep; frames with bad opcodes, no mask, 2^63-byte lengths,
# interleaved fragments), the server's answer to a valid evaluate checked
# every 500; it must still answer at the end and stop with status 0. With
# FUZZ (a script beside this one: serve_identify_fuzz.py, serve_uploads.py),
# that script's cases instead, the server given a --log-dir so that it takes
# uploads (and its pid in PIDLAB_SERVER_PID, the binary in PIDLAB_BIN).
# PIDLAB_SERVE_FLAGS, when set, adds flags to `pidlab serve` (--body-timeout 2).
#   serve_hostile_test.sh BIN_DIR COUNT SEED [FUZZ]
set -uo pipefail
bindir=$1 count=$2 seed=$3 fuzz=${4:-serve_fuzz.py}
here=$(cd "$(dirname -- "$0")" && pwd)
ip link set lo up || { echo "FAIL: cannot bring up the loopback"; exit 1; }
ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo 2>/dev/null
tmp=$(mktemp -d); trap 'kill $server 2>/dev/null; rm -rf "$tmp"' EXIT
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
logs=()
[ "$fuzz" = serve_fuzz.py ] || logs=(--log-dir "$tmp")
read -r -a extra <<< "${PIDLAB_SERVE_FLAGS:-}"
"$bindir/pidlab" serve --port 0 "${logs[@]}" "${extra[@]}" > "$tmp/out" 2> "$tmp/err" &
server=$!
export PIDLAB_SERVER_PID=$server PIDLAB_BIN=$bindir/pidlab  # for a script that reads the server's memory (serve_uploads.py)
for _ in $(seq 200); do grep -q '^pidlab serve: http' "$tmp/out" && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://[^/]*:([0-9]+)/.*#\1#p' "$tmp/out")
[ -n "$port" ] || { echo "FAIL: the server did not start"; cat "$tmp/err"; exit 1; }
/usr/bin/python3 "$here/$fuzz" "$port" "$count" "$seed" || echo "FAIL: the hostile input found a failure"
if kill -0 "$server" 2>/dev/null; then
  kill -TERM "$server"; wait "$server"; status=$?
  [ "$status" -eq 0 ] && echo "ok   the server stopped with status 0" || echo "FAIL: the server exited $status"
else
  wait "$server"; echo "FAIL: the server died (status $?)"
fi
cat "$tmp/err"
