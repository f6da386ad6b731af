"""The served evaluation's defaults against `pidlab evaluate --json` and
`pidlab plot` (tests/cli/serve_defaults_test.sh): each spec as the page
sends it, with only the fields the form sets (no horizon, no sample_time),
asked as a page does: over 2 WebSockets and HTTP at once, with the plot
series, each spec three times. The served result must equal evaluate's
object key for key (its time scale, its echoed spec, every number), the
series' time grid lie on the sampled loop's grid (a whole multiple of dt)
and end at its frame's horizon, and `pidlab plot` of the same flags draw the
same frame. Prints 'ok ...' lines and 'FAIL ...' on any failure.
  serve_defaults.py PORT PIDLAB"""
import json, os, subprocess, sys, tempfile, threading
from serve_client import http, WebSocket

port, pidlab = int(sys.argv[1]), sys.argv[2]
GAINS = [3.9, 0.06, 4.9]
SPECS = [
    {'plant': 'double_integrator', 'gains': GAINS, 'loop': 'sampled'},
    {'plant': 'custom', 'num': [1], 'den': [1, 0, 0], 'gains': GAINS, 'loop': 'sampled'},
    {'plant': 'custom', 'num': [1], 'den': [1, 0, 0], 'gains': GAINS},
    {'plant': 'double_integrator', 'gains': GAINS, 'loop': 'sampled', 'dt': 0.002},
    {'plant': 'oscillator', 'gains': [2, 1, 1.5], 'loop': 'sampled'},
    {'plant': 'stepper_motor', 'gains': [30, 0.5, 1], 'loop': 'sampled', 'dt': 0.0005},
    {'plant': 'custom', 'num': [1], 'den': [10, 1], 'delay': 0.5, 'gains': [1, 0.1, 0], 'loop': 'sampled',
     'dt': 0.01},
    {'plant': 'custom', 'num': [1], 'den': [100, 1], 'gains': [2, 0.05, 0], 'loop': 'sampled', 'dt': 1},
]
failures = 0
lock = threading.Lock()


def check(name, ok, detail=''):
    global failures
    with lock:
        if not ok: failures += 1
        print(('ok   ' if ok else 'FAIL ') + name + ('' if ok else ': ' + detail), flush=True)


def flags(spec):
    out = []
    for key, value in spec.items():
        text = ','.join(str(v) for v in value) if isinstance(value, list) else str(value)
        out += ['--' + key.replace('_', '-'), text]
    return out


def name(spec):
    return ' '.join(flags(spec))


# What the command line prints for each spec.
wanted = {}
for spec in SPECS:
    run = subprocess.run([pidlab, 'evaluate'] + flags(spec) + ['--json'], capture_output=True, text=True)
    check('pidlab evaluate %s exits 0' % name(spec), run.returncode == 0, run.stderr.strip())
    wanted[name(spec)] = json.loads(run.stdout) if run.returncode == 0 else None

# The same specs served, as a page asks: 4 WebSockets and HTTP at once.
served = {}  # name -> list of replies


def keep(spec, reply):
    with lock:
        served.setdefault(name(spec), []).append(reply)


def websocket_client(k):
    ws = WebSocket(port)
    for i, spec in enumerate(SPECS[k:] + SPECS[:k]):
        keep(spec, ws.ask({'id': i, 'type': 'evaluate', 'spec': spec}))


def http_client():
    for spec in reversed(SPECS):
        status, body = http(port, 'POST', '/api/request', json.dumps({'type': 'evaluate', 'spec': spec}).encode())
        keep(spec, json.loads(body) if status == 200 else {'error': '%d %s' % (status, body[:200])})


threads = [threading.Thread(target=websocket_client, args=(k,)) for k in range(2)]
threads += [threading.Thread(target=http_client)]
for t in threads: t.start()
for t in threads: t.join()

for spec in SPECS:
    key = name(spec)
    replies = served.get(key, [])
    errors = [r.get('error') for r in replies if 'error' in r]
    check('%s is served %d of %d times' % (key, len(replies) - len(errors), 3), len(replies) == 3 and not errors,
          str(errors)[:300])
    if errors or wanted[key] is None: continue
    want = wanted[key]
    same = all(r['result'] == want for r in replies)
    differing = sorted(k for k in set(want) | set(replies[0]['result']) if replies[0]['result'].get(k) != want.get(k))
    check('%s: the served result is evaluate --json\'s, key for key (time scale %s s, %s s)' % (
        key, want['time_scale']['horizon_s'], want['time_scale']['sample_time_s']), same, 'keys %s' % differing)
    series = replies[0]['series']
    frame = series['time_scale']
    t = series['t']
    sampled = spec.get('loop') == 'sampled'
    dt = want['spec']['dt'] if sampled else 0.0
    spacing = t[1] - t[0]
    on_grid = not sampled or all(abs(x / dt - round(x / dt)) < 1e-6 for x in t)
    check('%s: the figure\'s frame %s s at %s s lies on the loop\'s grid and ends at its horizon' % (
        key, frame['horizon_s'], frame['sample_time_s']),
        on_grid and abs(t[-1] - frame['horizon_s']) < 1e-9 * max(1.0, frame['horizon_s']) and
        abs(spacing - frame['sample_time_s']) < 1e-9 * max(1.0, spacing),
        't %s..%s step %s' % (t[0], t[-1], spacing))
    with tempfile.TemporaryDirectory() as out:
        run = subprocess.run([pidlab, 'plot'] + flags(spec) + ['--out', out], capture_output=True, text=True)
        ends = []
        data = os.path.join(out, 'evaluation_data')
        for f in os.listdir(data) if os.path.isdir(data) else []:
            if f.endswith('.dat'):
                rows = [line.split()[0] for line in open(os.path.join(data, f)) if line[:1] not in '#\n']
                if rows: ends.append(float(rows[-1]))
        # plot draws every step of the sampled loop: its last point one step (dt) or one
        # sample before the frame's horizon at most.
        reach = max(ends) if ends else float('nan')
        check('%s: pidlab plot draws the same frame (to %.6g s)' % (key, reach),
              run.returncode == 0 and frame['horizon_s'] - frame['sample_time_s'] - 1e-9 <= reach <=
              frame['horizon_s'] + 1e-9, 'exit %d %s, last point %s' % (run.returncode, run.stderr.strip(), reach))
sys.exit(1 if failures else 0)
