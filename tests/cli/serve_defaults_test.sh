#!/usr/bin/env bash
# The workbench's sampled defaults are the command line's (docs/workbench.md,
# "The protocol"): `pidlab serve`, in a private network namespace of its
# own, evaluates specs that set no horizon and no sample time (the sampled
# double integrator, 1/s^2, a thermal plant at dt = 1 s, ...) exactly as
# `pidlab evaluate --json` does, and frames their figures as `pidlab plot`
# does (tests/cli/serve_defaults.py). SIGTERM stops it with status 0.
#   serve_defaults_test.sh PIDLAB_BINARY
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
ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo 2>/dev/null
here=$(cd "$(dirname -- "$0")" && pwd)
tmp=$(mktemp -d); trap 'kill $server 2>/dev/null; rm -rf "$tmp"' EXIT
"$pidlab" serve --port 0 > "$tmp/out" 2> "$tmp/err" &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' "$tmp/out" && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://127\.0\.0\.1:([0-9]+)/$#\1#p' "$tmp/out")
[ -n "$port" ] || { echo "FAIL: the server did not start: $(head -c 300 "$tmp/out" "$tmp/err")"; exit 1; }
PYTHONPATH="$here" /usr/bin/python3 "$here/serve_defaults.py" "$port" "$pidlab" ||
  echo "FAIL: a served default differs from the command line's"
kill -TERM "$server"; wait "$server"; status=$?
[ "$status" -eq 0 ] && echo "ok   the server stopped with status 0" || echo "FAIL: the server exited $status"
