#!/usr/bin/env bash
# browser.bode_phase: the workbench's Bode plot of dead-time loops (issue 58)
# in Debian's headless Chromium at 1280x800 (tests/browser/bode_phase_test.js),
# in a private network namespace of its own (loopback only): on the tank, the
# motor and an integrating plant, each with its dead time, the drawn phase of
# L is the server's l_phase_deg and never jumps by more than 180 degrees
# between neighbouring points; its axis is clipped around the crossovers,
# with a note where the curve leaves it. The tank's Bode plot: OUT_DIR/bode-tank.png.
#   bode_phase_test.sh PIDLAB_BINARY SOURCE_DIR OUT_DIR
set -uo pipefail
if [[ $# -ne 3 ]]; then
  echo "usage: $0 PIDLAB_BINARY SOURCE_DIR OUT_DIR" >&2
  exit 2
fi
pidlab=$(realpath -- "$1") source_dir=$(realpath -- "$2") out_dir=$(realpath -m -- "$3")
# Not a skip: without the browser or the npm packages the test fails, with one line.
source "$(dirname -- "${BASH_SOURCE[0]}")/require_browser.sh" "$source_dir" || exit 1
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
ip link set lo up || { echo "FAIL: cannot bring up the private namespace's loopback"; exit 1; }
mkdir -p "$out_dir" && rm -f "$out_dir"/bode-*.png  # no stale screenshot from an earlier run
tmp=$(mktemp -d)
server=
trap '[ -n "$server" ] && kill "$server" 2>/dev/null; rm -rf "$tmp"' EXIT
"$pidlab" serve --port 0 --bind 127.0.0.1 > "$tmp/serve.out" 2> "$tmp/serve.err" &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' "$tmp/serve.out" && break; sleep 0.05; done
url=$(sed -n 's/^pidlab serve: //p' "$tmp/serve.out" | head -1)
if [[ ! $url =~ ^http://127\.0\.0\.1:[0-9]+/ ]]; then
  echo "FAIL: pidlab serve --port 0 printed no URL on 127.0.0.1: $(head -c 300 "$tmp/serve.out" "$tmp/serve.err")"
  exit 1
fi
# Bounded: the whole test well under ctest's TIMEOUT.
timeout 110 node "$source_dir/tests/browser/bode_phase_test.js" \
  --url "$url" --modules "$source_dir/node_modules" --chromium "$chromium" --out "$out_dir" --tmp "$tmp"
status=$?
[ $status -eq 124 ] && echo "FAIL: the browser test did not finish in 110 s"
kill -0 "$server" 2>/dev/null || { echo "FAIL: pidlab serve is no longer running"; status=1; }
exit $status
