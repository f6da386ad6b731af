#!/usr/bin/env bash
# pidlab serve (docs/workbench.md), in a private network namespace of its
# own: the page and its script are served; an evaluate request over HTTP and
# over the WebSocket gives exactly `pidlab evaluate --json`'s object, whose
# echoed spec reruns to the same numbers; a bad spec gets its validation
# message and the server keeps serving; another Origin or Host is refused,
# oversized and malformed requests are answered and bounded; bound beyond
# loopback the server prints a token and refuses requests without it; bad
# flags exit 2 with one line; SIGTERM stops it with status 0.
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
source "$here/stderr_shape.sh"
docs=$(cd "$here/../../docs" && pwd)/workbench.md
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'kill $server 2>/dev/null; rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
server=

"$pidlab" serve --help > help
check "serve --help exits 0 and names --port and --bind" "[ $? -eq 0 ] && grep -q -- '--port' help && grep -q -- '--bind' help"
for case in "--port 70000|port 70000 must be in 0..65535" "--bind nonsense|bind address 'nonsense'"; do
  args=${case%%|*} needle=${case#*|}
  "$pidlab" serve $args > out 2> err
  check "serve $args exits 2 with one line naming it" "[ $? -eq 2 ] && only_line_ok err \"$needle\" && [ ! -s out ]"
done

# Starts `pidlab serve ARGS` and waits for its URL line; sets url and port.
start() {
  "$pidlab" serve "$@" > serve.out 2> serve.err &
  server=$!
  for _ in $(seq 100); do grep -q '^pidlab serve: http' serve.out && break; sleep 0.05; done
  url=$(sed -n 's/^pidlab serve: //p' serve.out | head -1)
  port=$(sed -E 's#^http://[^/]*:([0-9]+)/.*#\1#' <<<"$url")
}

start --port 0
check "serve --port 0 prints its URL on 127.0.0.1 without a token" "[[ $url =~ ^http://127\.0\.0\.1:[0-9]+/$ ]]"
"$pidlab" evaluate --plant double_integrator --gains 3.9,0.06,4.9 --json > want.json
"$pidlab" evaluate --plant stepper_motor --gains 30,0.5,1 --loop sampled --dt 0.001 --json > want_sampled.json
"$pidlab" tune --plant double_integrator --robust --json > want_tune.json
"$pidlab" evaluate --plant oscillator --gains 2,1,1.5 --monte-carlo 20 --spread 0.2 --json > want_mc.json
echo '{"plant": "oscillator", "gains": [2, 1, 1.5], "loop": "sampled", "output_limits": [-5, 5]}' > export_spec.json
"$pidlab" export --spec export_spec.json --lang c --out exported > /dev/null
PYTHONPATH="$here" /usr/bin/python3 - "$port" "$pidlab" <<'PY'
import json, subprocess, sys
from serve_client import http, WebSocket
port = int(sys.argv[1])
def check(name, ok):
    print(('ok   ' if ok else 'FAIL ') + name)
status, body = http(port, 'GET', '/')
check('GET / is the page', status == 200 and b'pidlab workbench' in body and b'app.js' in body)
status, body = http(port, 'GET', '/app.js')
check('GET /app.js is the script', status == 200 and b'WebSocket' in body)
check('GET /nothing is 404', http(port, 'GET', '/nothing')[0] == 404)
want = json.load(open('want.json'))
spec = {'plant': 'double_integrator', 'gains': [3.9, 0.06, 4.9]}
status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'evaluate', 'spec': spec}).encode())
got = json.loads(body)
check('POST evaluate gives evaluate --json\'s object, key for key', status == 200 and got['result'] == want)
json.dump(got['result'], open('served.json', 'w'))
import csv
series = got.get('series', {})
frame = series.get('time_scale', {})
# The plots' frame is `pidlab plot`'s: the transient fills it (eq. (4)'s numbers stay in the result).
check('the series has its own frame, the figure\'s, shorter than eq. (4)\'s 25 s',
      frame.get('source') == 'plant' and 0 < frame.get('horizon_s', 0) < 25)
subprocess.run([sys.argv[2], 'evaluate', '--plant', 'double_integrator', '--gains', '3.9,0.06,4.9',
                '--horizon', repr(frame['horizon_s']), '--sample-time', repr(frame['sample_time_s']),
                '--samples-csv', 'samples.csv'], check=True, stdout=subprocess.DEVNULL)
rows = list(csv.DictReader(open('samples.csv')))
check('the reply\'s series y is --samples-csv\'s y on that frame, bit for bit',
      [float(r['y']) for r in rows] == series.get('y') and [float(r['t']) for r in rows] == series.get('t'))
ms = got['result']['robustness']['ms']  # at w = inf here: the grid's end comes within 1e-6
check('the reply\'s series has |S| peaking at the reported Ms and the Nyquist curve',
      ms * (1 - 1e-6) <= max(series['s']) <= ms * (1 + 1e-9)
      and len(series['l_re']) == len(series['w']) == len(series['t_mag']) == len(series['cs']))
check('the reply carries the server\'s compute time', isinstance(got.get('compute_ms'), float) and got['compute_ms'] > 0)
status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'evaluate', 'spec': spec, 'series': False}).encode())
check('"series": false leaves the series out', status == 200 and 'series' not in json.loads(body))
mc_spec = {'plant': 'oscillator', 'gains': [2, 1, 1.5], 'monte_carlo': 20, 'spread': 0.2}
status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'evaluate', 'spec': mc_spec}).encode())
got = json.loads(body)
band = got.get('series', {}).get('monte_carlo', {})
check('with monte_carlo the result is evaluate --monte-carlo --json\'s and the series has the band of 20 draws',
      status == 200 and got['result'] == json.load(open('want_mc.json')) and band.get('stable') == 20
      and all(lo <= hi for lo, hi in zip(band['y_min'], band['y_max'])))
status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'evaluate', 'spec': dict(mc_spec, monte_carlo=5000)}).encode())
check('more than 1000 Monte-Carlo draws are refused with one line', status == 400 and b'monte_carlo 5000' in body)
status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'paper_designs'}).encode())
designs = json.loads(body).get('designs', [])
table2 = [d for d in designs if d['table'] == 'II' and d['method'] == 'nelder_mead']
check('paper_designs lists the 13 published gain sets of Tables II-VI',
      status == 200 and len(designs) == 13 and table2 and table2[0]['gains'] == [29.6558, 0.4977, 28.3216])
export_spec = json.load(open('export_spec.json'))
status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'export', 'spec': export_spec}).encode())
files = json.loads(body).get('files', {})
check('export gives the files pidlab export --spec writes, byte for byte',
      status == 200 and files.get('pidlab_pid.h') == open('exported/pidlab_pid.h').read()
      and files.get('pidlab_pid.c') == open('exported/pidlab_pid.c').read())
status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'export', 'spec': {'plant': 'oscillator'}}).encode())
check('export without gains is refused with one line', status == 400 and b'gains are required' in body)
want_sampled = json.load(open('want_sampled.json'))
ws = WebSocket(port)
check('the WebSocket upgrade at /ws is accepted', ws.status == 101)
reply = ws.ask({'id': 41, 'type': 'evaluate', 'spec': want_sampled['spec']})
check('over the WebSocket a sampled spec gives evaluate --json\'s object and the id back',
      reply.get('id') == 41 and reply['result'] == want_sampled)
reply = ws.ask({'id': 42, 'type': 'evaluate', 'spec': {'plant': 'double_integrator', 'gains': [-1, 1, 0]}})
check('a bad spec gets its validation message naming the value', 'kp = -1' in reply.get('error', ''))
reply = ws.ask({'id': 43, 'type': 'evaluate', 'spec': {'plant': 'double_integrator', 'gainz': [1, 0, 0]}})
check('an unknown spec key is named', "spec key 'gainz' is unknown" in reply.get('error', ''))
ws.send('not json')
op, payload = ws.recv()
check('a message that is not JSON gets an error reply', b'one JSON object' in payload)
reply = ws.ask({'id': 44, 'type': 'fields'})
check('the fields request lists the spec\'s keys', any(f['key'] == 'gains' for f in reply['fields']))
want_tune = json.load(open('want_tune.json'))
ws.send(json.dumps({'id': 45, 'type': 'tune', 'spec': {'plant': 'double_integrator', 'robust': True}}))
kinds = []
while True:
    reply = json.loads(ws.recv()[1])
    kinds.append(reply.get('type'))
    if reply.get('type') != 'tune_progress': break
check('a tune request sends progress, then tune --robust --json\'s gains and objective',
      reply.get('id') == 45 and reply['type'] == 'tune_result' and kinds[0] == 'tune_progress'
      and reply['result']['gains'] == want_tune['gains'] and reply['result']['objective'] == want_tune['objective']
      and reply['result']['spec'] == want_tune['spec'])
ws.send(json.dumps({'id': 46, 'type': 'tune', 'spec': {'plant': 'oscillator', 'method': 'ga', 'loop': 'sampled', 'max_evals': 200000}}))
first = json.loads(ws.recv()[1])
busy = ws.ask({'id': 47, 'type': 'tune', 'spec': {'plant': 'oscillator'}})
ws.send(json.dumps({'type': 'tune_cancel'}))
while True:
    reply = json.loads(ws.recv()[1])
    if reply.get('id') == 46 and reply.get('type') != 'tune_progress': break
check('a second tuning on the connection is refused while one runs', 'already running' in busy.get('error', ''))
check('tune_cancel stops the running tuning', first.get('type') == 'tune_progress' and reply['type'] == 'tune_cancelled')
status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'tune', 'spec': {'plant': 'oscillator'}}).encode())
check('tune over HTTP is refused: it needs the WebSocket', status == 400 and b'WebSocket' in body)
try:
    ws.send('x' * 70000)
    op, payload = ws.recv()
    closed = op == 8
except (EOFError, ConnectionError):  # closed (or reset) while the rest was still being sent
    closed = True
check('a WebSocket message over 64 KiB closes that connection', closed)
check('after it the server still answers', http(port, 'GET', '/api/health')[0] == 200)
evil = WebSocket(port, origin='http://evil.example')
check('a WebSocket from another Origin is refused (403)', evil.status == 403)
check('a POST from another Origin is refused (403)',
      http(port, 'POST', '/api/request', b'{}', {'Origin': 'http://evil.example'})[0] == 403)
check('a request for another Host is refused (403)', http(port, 'GET', '/', headers={'Host': 'evil.example:%d' % port})[0] == 403)
check('a body over 64 KiB is refused (413)', http(port, 'POST', '/api/request', b'a' * 100000)[0] == 413)
check('a malformed request line gets 400', http(port, '', '', raw=b'GARBAGE\r\n\r\n')[0] == 400)
check('headers over 8 KiB get 431', http(port, 'GET', '/', headers={'X-Big': 'b' * 9000})[0] == 431)
status, body = http(port, 'POST', '/api/request', b'{"type": "evaluate"')
check('a body that is not JSON gets 400', status == 400 and b'one JSON object' in body)
check('and the page is still served', http(port, 'GET', '/')[0] == 200)
PY
check "the HTTP and WebSocket checks ran to their end" "[ $? -eq 0 ]"
/usr/bin/python3 -c "import json; print(json.dumps(json.load(open('served.json'))['spec']))" > spec.json
"$pidlab" evaluate --spec spec.json --json > rerun.json
check "the served result's spec reruns with evaluate --spec to the same IAE" \
  "/usr/bin/python3 -c \"import json; a = json.load(open('served.json')); b = json.load(open('rerun.json')); assert a['iae'] == b['iae'] and a == b\""
kill -TERM "$server"; wait "$server"; status=$?
check "SIGTERM stops the server with status 0" "[ $status -eq 0 ]"

start --port 0 --bind 0.0.0.0
check "bound to 0.0.0.0 it prints a URL with a 32-digit token" "[[ $url =~ \?token=[0-9a-f]{32}$ ]]"
token=${url##*token=}
PYTHONPATH="$here" /usr/bin/python3 - "$port" "$token" <<'PY'
import sys
from serve_client import http, WebSocket
port, token = int(sys.argv[1]), sys.argv[2]
def check(name, ok):
    print(('ok   ' if ok else 'FAIL ') + name)
check('without the token a request is refused (401)', http(port, 'GET', '/')[0] == 401)
check('with a wrong token too', http(port, 'GET', '/?token=' + '0' * 32)[0] == 401)
check('with the token in the URL the page is served', http(port, 'GET', '/?token=' + token)[0] == 200)
check('with the token as a bearer header the API answers',
      http(port, 'GET', '/api/health', headers={'Authorization': 'Bearer ' + token})[0] == 200)
check('a WebSocket without the token is refused (401)', WebSocket(port).status == 401)
check('a WebSocket with it is accepted', WebSocket(port, '/ws?token=' + token).status == 101)
PY
check "the token checks ran to their end" "[ $? -eq 0 ]"
kill -TERM "$server"; wait "$server"

# The commands of docs/workbench.md, as written there.
n_docs=0
while IFS= read -r cmd; do
  n_docs=$((n_docs + 1))
  args=${cmd#pidlab serve}
  start $args
  check "docs/workbench.md: $cmd starts and serves" "[[ $url =~ ^http:// ]]"
  kill -TERM "$server"; wait "$server"
done < <(awk '/^```bash/{on=1; next} /^```/{on=0} on && /^pidlab serve/' "$docs")
check "docs/workbench.md has 2 serve commands (found $n_docs)" "[ $n_docs -eq 2 ]"
server=
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
