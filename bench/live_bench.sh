#!/usr/bin/env bash
# The live scope's cost (issue 27): lockstep steps per second of `pidlab
# evaluate --backend lcm` (its steps_per_second) with one browser watching the
# Live tab against none, runs interleaved in one run (none, watched, none,
# watched, ...; the server runs with --lcm-url in both, the page is on the
# Design tab, unsubscribed, for "none"), and the page's frames per second
# (requestAnimationFrame, counted in the browser) while a trio at dt = 1e-4 s
# (10 kHz of simulated time, unpaced) streams. Headless Chromium through
# puppeteer-core (bench/live_bench.js), all in a private network namespace.
# Also the server's CPU time per lockstep step in each mode (/proc). Targets:
# ratio watched/none >= 0.9, page >= 30 fps. Prints the machine's load; exit 1
# when a target is missed.
#   bench/live_bench.sh [PIDLAB] [PAIRS]     (root; defaults build/bin/pidlab 5)
set -euo pipefail
case "${1:-}" in -h|--help) sed -n '2,14p' "$0"; exit 0 ;; esac
pidlab=${1:-}
[ -z "$pidlab" ] || pidlab=$(realpath -m -- "$pidlab")
cd "$(dirname "$0")/.."
pidlab=${pidlab:-build/bin/pidlab}
pairs=${2:-5}
chromium=/usr/bin/chromium
[ -x "$pidlab" ] || { echo "live_bench.sh: $pidlab is not an executable (build pidlab first)" >&2; exit 2; }
[[ $pairs =~ ^[1-9][0-9]?$ ]] || { echo "live_bench.sh: PAIRS '$pairs' must be 1..99" >&2; exit 2; }
if [ ! -x "$chromium" ] || [ ! -f node_modules/puppeteer-core/package.json ] || ! command -v node >/dev/null; then
  echo "live_bench.sh: Chromium, node or node_modules/puppeteer-core is missing (run scripts/install-deps.sh)" >&2
  exit 2
fi
if [[ ${PIDLAB_BENCH_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_BENCH_IN_NAMESPACE=1 exec unshare -n bash "$0" "$pidlab" "$pairs"
fi
ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo
export PATH="$(dirname "$(realpath "$pidlab")"):$PATH"
echo "machine: $(nproc) processors; uptime:$(uptime)"
tmp=$(mktemp -d)
server=
trap '[ -n "$server" ] && kill "$server" 2>/dev/null; rm -rf "$tmp"' EXIT
lcm_url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
"$pidlab" serve --port 0 --lcm-url "$lcm_url" > "$tmp/serve.out" 2> "$tmp/serve.err" &
server=$!
deadline=$((SECONDS + 10))
until grep -q '^pidlab serve: http' "$tmp/serve.out" || ((SECONDS > deadline)); do sleep 0.05; done
url=$(sed -n 's/^pidlab serve: //p' "$tmp/serve.out" | head -1)
[ -n "$url" ] || { echo "live_bench.sh: pidlab serve printed no URL: $(head -c 300 "$tmp/serve.err")" >&2; exit 1; }
node bench/live_bench.js --url "$url" --pidlab "$(realpath "$pidlab")" --modules "$PWD/node_modules" \
  --chromium "$chromium" --tmp "$tmp" --lcm-url "$lcm_url" --pairs "$pairs" --server-pid "$server"
