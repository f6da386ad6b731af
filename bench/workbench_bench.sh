#!/usr/bin/env bash
# The workbench's interactivity in the real browser (issue 26: from slider
# input to redrawn plots, median under 30 ms and p99 under 100 ms): `pidlab
# serve` and Debian's headless Chromium (puppeteer-core) in a private network
# namespace; for each paper plant MOVES kp slider moves (random kp within a
# decade, seeded), each waiting for its redraw; input -> drawn, the server's
# compute and the browser's render (reply -> drawn) reported apart, from the
# page's pidlab.timings (bench/workbench_bench.js). Prints the machine's load
# and, when it is built (next to PIDLAB with PIDLAB_BUILD_BENCH=ON, or where
# WAKEUP_BENCH says), bench/wakeup_bench's floor over 5 s, so that a loaded
# machine shows. Exit 1 when a plant misses a target.
#   bench/workbench_bench.sh [PIDLAB] [MOVES]     (root; defaults build/bin/pidlab 200)
set -euo pipefail
pidlab=${1:-}
[ -z "$pidlab" ] || pidlab=$(realpath -m -- "$pidlab")  # relative to where it is run from
cd "$(dirname "$0")/.."
pidlab=${pidlab:-build/bin/pidlab}
moves=${2:-200}
root=$PWD
chromium=/usr/bin/chromium
[ -x "$pidlab" ] || { echo "workbench_bench.sh: $pidlab is not an executable (build pidlab first)" >&2; exit 2; }
if [ ! -x "$chromium" ] || [ ! -f node_modules/puppeteer-core/package.json ] || ! command -v node >/dev/null; then
  echo "workbench_bench.sh: Chromium, node or node_modules/puppeteer-core is missing (run scripts/install-deps.sh)" >&2
  exit 2
fi
if [[ ${PIDLAB_BENCH_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_BENCH_IN_NAMESPACE=1 exec unshare -n bash "$0" "$pidlab" "$moves"
fi
ip link set lo up
echo "machine: $(nproc) processors; uptime:$(uptime)"
wakeup=${WAKEUP_BENCH:-$(dirname "$pidlab")/wakeup_bench}
if [ -x "$wakeup" ]; then
  echo "floor: $("$wakeup" 0.001 5 | tr '\n' ' ')"
else
  echo "floor: $wakeup not built (cmake -DPIDLAB_BUILD_BENCH=ON)"
fi
tmp=$(mktemp -d)
server=
trap '[ -n "$server" ] && kill "$server" 2>/dev/null; rm -rf "$tmp"' EXIT
"$pidlab" serve --port 0 > "$tmp/serve.out" 2> "$tmp/serve.err" &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' "$tmp/serve.out" && break; sleep 0.05; done
url=$(sed -n 's/^pidlab serve: //p' "$tmp/serve.out" | head -1)
[ -n "$url" ] || { echo "workbench_bench.sh: pidlab serve printed no URL" >&2; exit 1; }
echo "chromium: $("$chromium" --version 2>/dev/null | head -1); pidlab serve at $url"
status=0
node bench/workbench_bench.js --url "$url" --modules "$root/node_modules" --chromium "$chromium" \
  --tmp "$tmp" --moves "$moves" || status=$?
echo "uptime after:$(uptime)"
exit $status
