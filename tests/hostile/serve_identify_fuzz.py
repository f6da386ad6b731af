"""Hostile uploads and identify requests against a running `pidlab serve`
(tests/hostile/serve_identify_fuzz.py, run by serve_hostile_test.sh): seeded malformed CSV records uploaded
(POST /api/upload) and fitted, and malformed identify and identify_cancel
requests on the WebSocket. Every identify gets exactly one answer (an error
at once, or identify_result / identify_cancelled), never a crash; the
server's health (an evaluate and a good fit) is checked every 500 cases.
Prints one line per class and 'FAIL ...' on any failure."""
import json, math, os, random, socket, sys, time
sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', 'cli'))
from serve_client import http, WebSocket

port, count, seed = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
rng = random.Random(seed)
failures = 0
next_id = 0


def fail(msg):
    global failures
    failures += 1
    print('FAIL ' + msg, flush=True)


def good_csv(rows=40):
    lines = ['t,u,y']
    for k in range(rows):
        t = k * 0.5
        u = 1.0 if t >= 2 else 0.0
        y = 2 * (1 - math.exp(-(t - 3) / 4)) if t >= 3 else 0.0
        lines.append('%g,%g,%.6f' % (t, u, y))
    return ('\n'.join(lines) + '\n').encode()


GOOD = good_csv()


def mutate(data):
    b = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        op = rng.randrange(4)
        i = rng.randrange(len(b) + 1)
        if op == 0 and b: b[min(i, len(b) - 1)] = rng.randrange(256)
        elif op == 1: b[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 16)))
        elif op == 2 and b: del b[i:i + rng.randint(1, 64)]
        else: b[i:i] = rng.choice([b'\r\n', b',', b'"', b'""', b'nan', b'inf', b'-1e308', b'1e999', b'\xef\xbb\xbf',
                                   b'\x00', b't,u,y\n', b',,,,', b'\n\n\n', b'0,0,0\n' * 3, b'\xff\xfe'])
    return bytes(b)


def hostile_csv():
    k = rng.randrange(6)
    if k == 0: return bytes(rng.randrange(256) for _ in range(rng.randint(1, 3000)))
    if k == 1: return b't,u,y\n' + b'0,0,0\n' * rng.randint(0, 3)  # too short, constant
    if k == 2: return b'"' * rng.randint(1, 20000)
    if k == 3: return b't,u,y\n' + b''.join(b'%d,%s,1\n' % (i, rng.choice([b'1', b'nan', b'inf', b'x'])) for i in range(50))
    if k == 4:  # well-formed numbers the fit must survive: extremes, steps in time, spikes
        scale = 10.0 ** rng.randint(-300, 300)
        rows, t = [], 0.0
        steps = [0.5] if rng.random() < 0.6 else [0.5, 0.5, 0.5, 1e-9, 1e6, 0.0, -0.5]
        for j in range(rng.randint(5, 60)):
            t += rng.choice(steps)
            rows.append('%r,%r,%r' % (t, rng.choice([0.0, 1.0, scale]), rng.gauss(0, 1) * rng.choice([1.0, scale])))
        return ('t,u,y\n' + '\n'.join(rows) + '\n').encode()
    return mutate(GOOD)


def upload(body, name):
    try:
        status, reply = http(port, 'POST', '/api/upload?name=' + name, body,
                             headers={'Content-Type': 'application/octet-stream'})
    except (ConnectionError, OSError, socket.timeout) as e:
        fail('the upload of %d bytes got no answer: %r' % (len(body), e))
        return None
    if status not in (200, 400, 413):
        fail('the upload answered %d %r' % (status, reply[:100]))
    return json.loads(reply).get('log_id') if status == 200 else None


class Session:
    def __init__(self):
        self.ws = WebSocket(port)
        self.ws.s.settimeout(60)

    def request(self, obj):
        """Sends obj with a fresh id; the final answer to it (an error, identify_result, identify_cancelled, ...)."""
        global next_id
        next_id += 1
        obj = dict(obj, id=next_id) if isinstance(obj, dict) else obj
        self.ws.send(json.dumps(obj) if not isinstance(obj, (bytes, str)) else obj)
        if not isinstance(obj, dict): return None
        while True:
            op, payload = self.ws.recv()
            m = json.loads(payload)
            if m.get('type') == 'identify_progress': continue
            if m.get('id') == next_id: return m


def hostile_request(upload_id):
    base = {'type': 'identify', 'upload_id': upload_id, 'model': 'p1d'}
    k = rng.randrange(10)
    if k == 0: base['model'] = rng.choice(['', 'P1D', 'tf', 'auto ', 'p9d', 'x' * 10000, 7, None, [], {}])
    elif k == 1: base['upload_id'] = rng.choice(['', 'log0', 'log99999', '../etc/passwd', 1e308, -1, None, [1], {'a': 1}])
    elif k == 2: base = {'type': 'identify', 'log_id': rng.choice(['log1', 'x', 3, None]), 'index': rng.choice([0, -1, 1e9, 'a', None]), 'model': 'p1d'}
    elif k == 3: base.update(model='tf', poles=rng.choice([0, -1, 99, 1.5, 'a', None, 2 ** 40]), zeros=rng.choice([0, -1, 5, 'x']))
    elif k == 4: base['u0'] = rng.choice(['estimate', 'est', 1e308, -1e308, None, [], 'nan', {}, 0, 1])
    elif k == 5: base['poles'] = 2
    elif k == 6: base = {'type': 'identify'}
    elif k == 7: base['upload_id'] = upload_id; base['log_id'] = 'log1'
    elif k == 8: return {'type': 'identify_cancel'}
    else: base['model'] = 'p2d'
    return base


def ask_ok(session, obj, what):
    try:
        return session.request(obj)
    except (ConnectionError, OSError, socket.timeout, EOFError, ValueError) as e:
        fail('%s: no answer: %r' % (what, e))
        return None


def healthy(session, where):
    status, body = http(port, 'POST', '/api/request', json.dumps(
        {'type': 'evaluate', 'spec': {'plant': 'double_integrator', 'gains': [3.9, 0.06, 4.9]}}).encode())
    if status != 200 or b'"iae"' not in body: fail('after %s evaluate answered %d %r' % (where, status, body[:100]))
    uid = upload(GOOD, 'good.csv')
    m = ask_ok(session, {'type': 'identify', 'upload_id': uid, 'model': 'p1d'}, 'the good fit after ' + where)
    if not m or m.get('type') != 'identify_result' or 'result' not in m:
        fail('after %s the good fit answered %r' % (where, (m or {}))) if m is not None else None
    elif abs(m['result']['parameters']['Kp']['value'] - 2) > 1e-3:
        fail('after %s the good fit gave Kp %r' % (where, m['result']['parameters']['Kp']['value']))


start = time.time()
session = Session()
uploads = count // 5
names = ['r.csv', 'a b.csv', '../x.csv', '.hidden', 'x' * 200, 'ok.csv', '%00.csv', 'é.csv']
answered = fitted = 0
for i in range(uploads):
    uid = upload(hostile_csv(), rng.choice(names) if rng.random() < 0.2 else 'r%d.csv' % i)
    if uid is not None:
        m = ask_ok(session, {'type': 'identify', 'upload_id': uid, 'model': rng.choice(['p1d'] * 9 + ['p2d'])}, 'upload %d' % i)
        if m is not None:
            answered += 1
            fitted += 1 if 'result' in m else 0
            if m.get('type') not in ('identify_result', 'identify_cancelled') and 'error' not in m:
                fail('upload %d: the identify answer %r' % (i, m))
    if (i + 1) % 500 == 0: healthy(session, '%d hostile uploads' % (i + 1))
print('ok   %d hostile CSV uploads: %d stored and answered by identify (%d fitted, %d refused with one line)'
      % (uploads, answered, fitted, answered - fitted), flush=True)
uid = upload(GOOD, 'base.csv')
for i in range(count - uploads):
    obj = hostile_request(uid)
    if rng.random() < 0.05:  # not JSON at all, or a bare value
        try:
            session.ws.send(rng.choice(['{"type": "identify"', '[]', 'null', '{"type":"identify","model":"p1d","upload_id":' + '[' * 5000]))
        except (ConnectionError, OSError) as e:
            fail('a bad text frame: %r' % e)
            session = Session()
        continue
    m = ask_ok(session, obj, 'identify request %d' % i)
    if m is None:
        session = Session()
    elif obj.get('type') == 'identify' and m.get('type') not in ('identify_result', 'identify_cancelled') and 'error' not in m:
        fail('identify request %d answered %r' % (i, m))
    if (i + 1) % 500 == 0: healthy(session, '%d hostile identify requests' % (i + 1))
print('ok   %d hostile identify and identify_cancel requests, each answered' % (count - uploads), flush=True)
healthy(session, 'everything')
print('%d cases in %.1f s, %d failures' % (count, time.time() - start, failures))
sys.exit(1 if failures else 0)
