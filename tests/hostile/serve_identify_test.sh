#!/usr/bin/env bash
# Hostile uploads and identify requests against `pidlab serve` (docs/workbench.md,
# "From data to C"), in a private network namespace: COUNT seeded cases
# (a fifth malformed CSV records uploaded and fitted, the rest malformed
# identify and identify_cancel requests), health checked every 500; the
# server must still answer at the end and stop with status 0.
#   serve_identify_test.sh PIDLAB_BINARY COUNT SEED
set -uo pipefail
pidlab=$1 count=$2 seed=$3
here=$(cd "$(dirname -- "$0")" && pwd)
ip link set lo up || { echo "FAIL: cannot bring up the loopback"; exit 1; }
tmp=$(mktemp -d); trap 'kill $server 2>/dev/null; rm -rf "$tmp"' EXIT
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
"$pidlab" serve --port 0 --log-dir "$tmp" > "$tmp/out" 2> "$tmp/err" &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' "$tmp/out" && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://[^/]*:([0-9]+)/.*#\1#p' "$tmp/out")
[ -n "$port" ] || { echo "FAIL: the server did not start"; cat "$tmp/err"; exit 1; }
/usr/bin/python3 "$here/serve_identify_fuzz.py" "$port" "$count" "$seed" || echo "FAIL: the hostile input found a failure"
if kill -0 "$server" 2>/dev/null; then
  kill -TERM "$server"; wait "$server"; status=$?
  [ "$status" -eq 0 ] && echo "ok   the server stopped with status 0" || echo "FAIL: the server exited $status"
else
  wait "$server"; echo "FAIL: the server died (status $?)"
fi
cat "$tmp/err"
