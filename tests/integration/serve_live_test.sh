#!/usr/bin/env bash
# pidlab serve --lcm-url (docs/live.md), in a private network namespace of its
# own: with a trio started by `pidlab launch`, a WebSocket client subscribes
# to the live scope while `pidlab evaluate --backend lcm` runs an episode; the
# final kind-2 frame equals the episode's trajectory bit for bit, the status
# shows it complete, live_data answers the same, run_on_trio agrees with the
# prediction bit for bit; without --lcm-url the live requests answer 400 and
# --auth-key or --channel-prefix exit 2 with one line; with an auth key a
# forged message is not shown and is counted. The trio parts run the commands
# of docs/live.md as written there. Two trios of `pidlab launch --trios 2` are
# watched at once while `pidlab tune` runs its episodes on both. A slow
# client's view frames are dropped (latest wins) and counted.
set -uo pipefail
if [[ $# -ne 2 ]]; then
  echo "usage: $0 PIDLAB_BINARY PYTHON_MESSAGES_DIR" >&2
  exit 2
fi
pidlab=$(realpath -- "$1")
messages=$(realpath -- "$2")  # the messages as Python classes (lcm-gen), to forge one
here=$(cd "$(dirname -- "$0")" && pwd)
cli=$(cd "$here/../cli" && pwd)  # stderr_shape.sh and serve_client.py, shared with the CLI tests
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo || {
  echo "FAIL: cannot route multicast over the private namespace's loopback"
  exit 1
}
source "$cli/stderr_shape.sh"
docs=$(cd "$here/../../docs" && pwd)/live.md
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
PYTHONPATH="$cli" /usr/bin/python3 - "$port" > plain.out <<'PY'
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

# The live scope on a trio, with the commands of docs/live.md as written there:
# each bash block starts the trio (`pidlab launch ...`, waited for until it
# says it is ready), the server (`pidlab serve ...`, until it prints its URL)
# and has the client run the block's `pidlab evaluate ...` while it watches.
# A block's other lines (the key file) run first.
run_block() {
  local mode=$1 launch=$2 serve=$3 evaluate=$4 line words
  rm -f launch.err serve.out
  eval "words=($launch)"; "$pidlab" "${words[@]:1}" > launch.out 2> launch.err &
  local trio=$!
  for _ in $(seq 200); do grep -q 'trio ready' launch.err && break; sleep 0.05; done
  eval "words=($serve)"; "$pidlab" "${words[@]:1}" > serve.out 2> serve.err &
  local server=$!
  for _ in $(seq 200); do grep -q '^pidlab serve: http' serve.out && break; sleep 0.05; done
  port=$(sed -nE 's#^pidlab serve: http://[^/]*:([0-9]+)/.*#\1#p' serve.out | head -1)
  eval "words=($evaluate)"
  PYTHONPATH="$here:$cli" timeout 200 /usr/bin/python3 "$here/serve_live_client.py" "$port" "$PWD" "$mode" \
    "$messages" "$pidlab" "${words[@]:1}" > client.out 2>&1
  local status=$?
  sed "s/^/  [$mode] /" client.out
  check "docs/live.md block $mode: the live scope's checks pass (exit $status)" \
    "[ $status -eq 0 ] && ! grep -q '^FAIL' client.out"
  kill -TERM "$server"; wait "$server"
  check "docs/live.md block $mode: SIGTERM stops the live server with status 0" "[ $? -eq 0 ]"
  kill -INT "$trio"; wait "$trio"
}
n_blocks=0
while IFS= read -r -d $'\x1e' block; do
  launch=$(grep '^pidlab launch' <<<"$block") serve=$(grep '^pidlab serve' <<<"$block")
  evaluate=$(grep '^pidlab evaluate' <<<"$block")
  grep -v '^pidlab ' <<<"$block" | grep . > setup.sh && bash setup.sh
  mode=plain; [[ $serve == *--auth-key* ]] && mode=auth; [[ $launch == *--realtime* ]] && mode=realtime
  n_blocks=$((n_blocks + 1))
  run_block "$mode" "$launch" "$serve" "$evaluate"
done < <(awk '/^```bash/{on=1; next} /^```/{if (on) printf "\x1e"; on=0} on' "$docs")
check "docs/live.md has 3 blocks of commands (found $n_blocks)" "[ $n_blocks -eq 3 ]"

# Several trios (`pidlab launch --trios 2`) watched at once while a tuning
# runs its episodes on both: every episode shown with its trio, each trio's
# health listed with its URL.
cat > trios.sh <<'TRIOS'
set -u
pidlab=$1 cli=$2
"$pidlab" serve --port 0 --lcm-url "$PIDLAB_LCM_URLS" > trios_serve.out 2> trios_serve.err &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' trios_serve.out && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://[^/]*:([0-9]+)/.*#\1#p' trios_serve.out | head -1)
PYTHONPATH="$cli" timeout 120 /usr/bin/python3 - "$port" "$pidlab" "$PIDLAB_LCM_URLS" <<'PY'
import json, re, subprocess, sys, time
from serve_client import WebSocket
port, pidlab, urls = int(sys.argv[1]), sys.argv[2], re.split('[ ,]+', sys.argv[3].strip())
ws = WebSocket(port); ws.s.settimeout(30)
ws.send(json.dumps({'type': 'live_subscribe'}))
tune = subprocess.run([pidlab, 'tune', '--backend', 'lcm', '--plant', 'oscillator', '--loop', 'sampled', '--dt', '0.01',
                       '--horizon', '2', '--max-evals', '12', '--starts', '2', '--json', '--quiet'],
                      stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
print(('ok   ' if tune.returncode == 0 else 'FAIL ') + 'pidlab tune --backend lcm ran over both trios')
tuned = json.loads(tune.stdout) if tune.returncode == 0 else {}
status, deadline = None, time.monotonic() + 20
while time.monotonic() < deadline:
    op, payload = ws.recv()
    if op != 1: continue
    m = json.loads(payload)
    if m.get('type') != 'live_status': continue
    status = m
    eps = m['episodes']
    done = [t for t in m.get('tunings', []) if t['status'] == 'done']
    if eps and all(e['status'] == 'complete' for e in eps) and {1, 2} <= {e['trio'] for e in eps} and done: break
eps = status['episodes'] if status else []
ok = bool(eps) and all(e['status'] == 'complete' for e in eps) and {e['trio'] for e in eps} == {1, 2}
print(('ok   ' if ok else 'FAIL ') + 'the tuning\'s %d episodes show complete, from trio 1 and trio 2' % len(eps))
trios = status.get('trios', []) if status else []
ok = [t['lcm_url'] for t in trios] == urls and all(t['health']['roles']['plant']['pid'] for t in trios)
print(('ok   ' if ok else 'FAIL ') + 'live_status lists each trio with its URL and its plant heard')
tunings = status.get('tunings', []) if status else []
t = tunings[-1] if tunings else {}
ok = (len(tunings) == 1 and t['status'] == 'done' and t['trios'] == 2 and t['evaluations'] == tuned.get('evaluations')
      and t['best_gains'] == [tuned['gains'][k] for k in ('kp', 'ki', 'kd')] and t['best_objective'] == tuned.get('objective'))
print(('ok   ' if ok else 'FAIL ') + 'the tuning is in live_status: done over 2 trios, its evaluations, best gains and objective '
      'those tune --json printed: %s' % json.dumps(t))
PY
status=$?
kill -TERM "$server"; wait "$server" || status=1
exit $status
TRIOS
timeout 200 "$pidlab" launch --quiet --trios 2 -- bash trios.sh "$pidlab" "$cli" > trios.out 2> trios.err
status=$?
sed 's/^/  [trios] /' trios.out
check "two trios watched at once (exit $status)" "[ $status -eq 0 ] && ! grep -q '^FAIL' trios.out"
[ $status -eq 0 ] || tail -n 5 trios.err

# A slow client (a 4 KiB receive buffer, not reading while a 50 001-step
# episode streams 4096-column views of 98 KB): views are replaced, not
# queued, and counted in its frames' headers and its live_status; the final
# kind-2 frame is never dropped.
cat > slow.sh <<'SLOW'
set -u
pidlab=$1 cli=$2
"$pidlab" serve --port 0 --lcm-url "$PIDLAB_LCM_URL" > slow_serve.out 2> slow_serve.err &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' slow_serve.out && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://[^/]*:([0-9]+)/.*#\1#p' slow_serve.out | head -1)
PYTHONPATH="$cli" timeout 120 /usr/bin/python3 - "$port" "$pidlab" <<'PY'
import json, socket, struct, subprocess, sys
import serve_client
def small_buffer_connection(address, timeout=None):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.settimeout(timeout)
    s.connect(address)
    return s
serve_client.socket.create_connection = small_buffer_connection
ws = serve_client.WebSocket(int(sys.argv[1])); ws.s.settimeout(60)
ws.send(json.dumps({'type': 'live_subscribe', 'columns': 4096}))
run = subprocess.run([sys.argv[2], 'evaluate', '--backend', 'lcm', '--plant', 'oscillator', '--gains', '2,1,1.5',
                      '--loop', 'sampled', '--dt', '0.0001', '--horizon', '5'], stdout=subprocess.DEVNULL)
final = None
while final is None:
    op, payload = ws.recv()
    if op == 2 and struct.unpack_from('<I', payload, 4)[0] == 2: final = struct.unpack_from('<8d', payload, 8)
# A status posted after the final frame: subscribing again makes the scope
# post one (the replies and frames go before any waiting status, so the one
# read next may be older); its count of this connection's drops only grows.
ws.send(json.dumps({'type': 'live_subscribe', 'columns': 4096}))
dropped = None
try:
    while dropped is None or dropped < final[7]:
        op, payload = ws.recv()
        m = json.loads(payload) if op == 1 else {}
        if m.get('type') == 'live_status': dropped = m['dropped_frames']
except OSError as e:
    print('no status counting them within 60 s: %s' % e)
def check(name, ok): print(('ok   ' if ok else 'FAIL ') + name)
check('the episode ran', run.returncode == 0)
check('the final frame came whole (50 001 steps) with dropped views counted (%d)' % final[7],
      final[2] == 50001 and final[6] == 50001 and final[7] > 0)
check('live_status counts the same connection\'s dropped frames (%s)' % dropped,
      dropped is not None and dropped >= final[7])
PY
status=$?
kill -TERM "$server"; wait "$server" || status=1
exit $status
SLOW
timeout 200 "$pidlab" launch --quiet -- bash slow.sh "$pidlab" "$cli" > slow.out 2> slow.err
status=$?
sed 's/^/  [slow] /' slow.out
check "a slow client's views are dropped and counted (exit $status)" "[ $status -eq 0 ] && ! grep -q '^FAIL' slow.out"
[ $status -eq 0 ] || tail -n 5 slow.err

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
