"""A long record on the workbench (docs/identify.md, "Long records"), run by
serve_hostile_test.sh against a `pidlab serve` with uploads: a 200 000-row
CSV of a first-order step with delay and noise (seeded, written here) is
uploaded; a P1D fit of it answers with the record decimated by 20 and the
gain and time constant within 3 % of the truth; a fit (auto, every kind)
cancelled once it has passed P1D answers identify_cancelled within 1 s,
and the server then uses no CPU to speak of (its utime + stime over the
next second under 0.25 s). The COUNT and SEED arguments are taken for the
runner's sake. Prints one line per check, 'FAIL ...' on a failure."""
import json, math, os, random, sys, time
sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', 'cli'))
from serve_client import http, WebSocket

port = int(sys.argv[1])
failures = 0
KP, TAU, TD, DT, ROWS = 2.0, 40.0, 5.0, 0.01, 200000


def check(ok, what):
    global failures
    failures += 0 if ok else 1
    print(('ok   ' if ok else 'FAIL ') + what, flush=True)


def record():
    rng = random.Random(59)
    lines, y, a = ['t,u,y'], 0.0, math.exp(-DT / TAU)
    for k in range(ROWS):
        t = k * DT
        u = 1.0 if t >= 100.0 else 0.0
        lines.append('%.2f,%g,%.6f' % (t, u, y + rng.gauss(0.0, 0.02)))
        # The exact ZOH step of Kp / (1 + tau s) with its delay (a whole number of samples).
        u_delayed = 1.0 if t - TD >= 100.0 - 1e-9 else 0.0
        y = a * y + KP * (1.0 - a) * u_delayed
    return ('\n'.join(lines) + '\n').encode()


def cpu_seconds(pid):
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


status, reply = http(port, 'POST', '/api/upload?name=long.csv', record(),
                     headers={'Content-Type': 'application/octet-stream'})
check(status == 200, 'the 200 000-row CSV is uploaded (%d)' % status)
upload_id = json.loads(reply).get('log_id')
ws = WebSocket(port)
ws.s.settimeout(120)


def answer(request_id):
    """The first message for request_id that is not progress, and the progress seen before it."""
    progress = 0
    while True:
        m = json.loads(ws.recv()[1])
        if m.get('id') != request_id: continue
        if m.get('type') == 'identify_progress':
            progress += 1
            continue
        return m, progress


ws.send(json.dumps({'type': 'identify', 'upload_id': upload_id, 'model': 'p1d', 'u0': 0, 'id': 1}))
m, progress = answer(1)
result = m.get('result', {})
decimation = result.get('decimation', {})
check(m.get('type') == 'identify_result' and decimation.get('factor') == 20 and decimation.get('samples') == 10000,
      'the P1D fit answers with the record decimated by 20 to 10000 samples: %s %s'
      % (decimation, m.get('error', '')))
parameters = {k: v['value'] for k, v in result.get('parameters', {}).items()}
close = all(abs(parameters.get(k, math.inf) - v) <= 0.03 * v for k, v in (('Kp', KP), ('Tp1', TAU)))
check(close, 'on the decimated record Kp and Tp1 are within 3 %% of %g and %g: %s' % (KP, TAU, parameters))
check(len(m.get('fit', {}).get('t', [])) == 10000, 'the fit\'s curves are the decimated record\'s')

ws.send(json.dumps({'type': 'identify', 'upload_id': upload_id, 'model': 'auto', 'u0': 0, 'id': 2}))
while True:
    m = json.loads(ws.recv()[1])
    # Deep in the fit: a kind of three or more parameters' solves, not P1D's.
    if m.get('type') == 'identify_progress' and m.get('id') == 2 and m.get('model') not in ('p1d', None): break
    if m.get('id') == 2 and m.get('type') != 'identify_progress':
        check(False, 'the auto fit answered before any progress: %s' % str(m)[:200])
        sys.exit(1)
asked = time.monotonic()
ws.send(json.dumps({'type': 'identify_cancel'}))
while True:
    m = json.loads(ws.recv()[1])
    if m.get('type') in ('identify_cancelled', 'identify_result'): break
latency = time.monotonic() - asked
check(m.get('type') == 'identify_cancelled' and latency < 1.0,
      'a cancelled fit answers identify_cancelled within 1 s: %s after %.3f s' % (m.get('type'), latency))
pid = int(os.environ['PIDLAB_SERVER_PID'])
before = cpu_seconds(pid)
time.sleep(1.0)
busy = cpu_seconds(pid) - before
check(busy < 0.25, 'after the cancel the server used %.2f s of CPU in 1 s (under 0.25)' % busy)
print('figures: cancel latency %.3f s' % latency, flush=True)
sys.exit(1 if failures else 0)
