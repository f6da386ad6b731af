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
# machine shows; then the same number of requests from a Python WebSocket
# client, without the browser. Exit 1 when a plant misses a target.
# With --any-plant (first): the 33 plants of bench/any_plant_bench.sh instead, the
# kp slider and the response-time knob (a migo design, then its evaluation) MOVES
# times each on every plant.
#   bench/workbench_bench.sh [--any-plant] [PIDLAB] [MOVES]     (root; defaults build/bin/pidlab 200, 10 with --any-plant)
set -euo pipefail
case "${1:-}" in -h|--help) sed -n '2,17p' "$0"; exit 0 ;; esac
any_plant=0
if [ "${1:-}" = --any-plant ]; then any_plant=1; shift; fi
pidlab=${1:-}
[ -z "$pidlab" ] || pidlab=$(realpath -m -- "$pidlab")  # relative to where it is run from
cd "$(dirname "$0")/.."
pidlab=${pidlab:-build/bin/pidlab}
moves=${2:-$([ $any_plant = 1 ] && echo 10 || echo 200)}
root=$PWD
chromium=/usr/bin/chromium
[ -x "$pidlab" ] || { echo "workbench_bench.sh: $pidlab is not an executable (build pidlab first)" >&2; exit 2; }
if [ ! -x "$chromium" ] || [ ! -f node_modules/puppeteer-core/package.json ] || ! command -v node >/dev/null; then
  echo "workbench_bench.sh: Chromium, node or node_modules/puppeteer-core is missing (run scripts/install-deps.sh)" >&2
  exit 2
fi
if [[ ${PIDLAB_BENCH_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_BENCH_IN_NAMESPACE=1 exec unshare -n bash "$0" $([ $any_plant = 1 ] && echo --any-plant) "$pidlab" "$moves"
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
if [ $any_plant = 1 ]; then
  # NAME|num|den|delay of every plant of the "any plant" batch.
  sed -n 's/^  "\([^|]*\)|[^|]*|--num \([^ ]*\) --den \([^ ]*\)\( --delay \([^ "]*\)\)\{0,1\}"$/\1|\2|\3|\5/p' \
    bench/any_plant_bench.sh > "$tmp/plants"
  echo "the any-plant batch: $(wc -l < "$tmp/plants") plants, $moves moves of each control"
  node bench/workbench_bench.js --url "$url" --modules "$root/node_modules" --chromium "$chromium" \
    --tmp "$tmp" --moves "$moves" --plants "$tmp/plants" || status=$?
  echo "uptime after:$(uptime)"
  exit $status
fi
node bench/workbench_bench.js --url "$url" --modules "$root/node_modules" --chromium "$chromium" \
  --tmp "$tmp" --moves "$moves" || status=$?
# The same requests without the browser: what the server and the loopback
# take, and Python's parse of the reply (its round trip), for comparison
# with the browser's "wire".
port=$(sed -E 's#^http://[^/]*:([0-9]+)/.*#\1#' <<<"$url")
PYTHONPATH="$root/tests/cli" /usr/bin/python3 - "$port" "$moves" <<'PY' || status=1
import math, random, sys, time
from serve_client import WebSocket
port, moves = int(sys.argv[1]), int(sys.argv[2])
rng = random.Random(26)
ws = WebSocket(port)
pct = lambda v, q: sorted(v)[max(0, math.ceil(q * len(v)) - 1)]  # nearest rank
print('without the browser (a Python WebSocket client, %d requests per plant, kp = 3.9 * 10^(u - 0.5)):' % moves)
for plant in ['double_integrator', 'oscillator', 'stepper_motor']:
    trip, server = [], []
    for i in range(moves):
        spec = {'plant': plant, 'gains': [float('%.6g' % (3.9 * 10 ** (rng.random() - 0.5))), 0.06, 4.9]}
        t0 = time.perf_counter()
        reply = ws.ask({'id': i + 1, 'type': 'evaluate', 'spec': spec})
        trip.append(1e3 * (time.perf_counter() - t0))
        server.append(reply['compute_ms'])
    print('  %-18s round trip med/p99 %5.1f %6.1f ms   server med/p99 %5.1f %5.1f ms' %
          (plant, pct(trip, 0.5), pct(trip, 0.99), pct(server, 0.5), pct(server, 0.99)))
PY
echo "uptime after:$(uptime)"
exit $status
