"""Bodies that trickle against a running `pidlab serve --body-timeout 2
--log-dir DIR` (tests/hostile/serve_hostile_test.sh with PIDLAB_SERVE_FLAGS,
which exports PIDLAB_BIN). At once, as a page's tabs and a slow client would:
6 request bodies and one 60 MiB upload, each trickling a byte (the upload a
KiB) every 0.25 s, so that no pause ever nears the deadline; a body of 2000
bytes sent in 6 parts over 1.2 s; a second 60 MiB upload while the first holds
the budget of uploads in memory; /api/health from 127.0.0.2 and a WebSocket
evaluation, every 0.25 s. Every trickling body must be answered 408 with one
line naming the deadline, 1.9 to 3.5 s after its header; the slow complete
body 200; the second upload 413; health and the evaluation answered within 1 s
throughout; and once the trickling upload is cut, a 60 MiB upload is stored
(the budget given back). Then bad --body-timeout values: exit 2, one line.
COUNT and SEED are taken, as serve_hostile_test.sh passes them, and ignored.
  serve_body_deadline.py PORT COUNT SEED"""
import json, os, socket, subprocess, sys, threading, time
sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', 'cli'))
from serve_client import WebSocket

port = int(sys.argv[1])
DEADLINE_S, TICK_S = 2.0, 0.25
UPLOAD_BYTES = 60 << 20
failures = 0
lock = threading.Lock()


def fail(msg):
    global failures
    with lock:
        failures += 1
        print('FAIL ' + msg, flush=True)


def header(path, length, source='127.0.0.1'):
    s = socket.create_connection(('127.0.0.1', port), timeout=10, source_address=(source, 0))
    s.sendall(b'POST %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nContent-Type: application/json\r\n'
              b'Content-Length: %d\r\nConnection: close\r\n\r\n' % (path.encode(), port, length))
    return s


def reply_of(s):
    """(status, body) of the reply on `s` (0 when the connection ended without one)."""
    data = b''
    try:
        while True:
            chunk = s.recv(65536)
            if not chunk: break
            data += chunk
    except OSError:
        pass
    s.close()
    head, _, body = data.partition(b'\r\n\r\n')
    parts = head.split(b' ')
    return (int(parts[1]) if len(parts) > 1 and parts[1].isdigit() else 0), body


def trickle(results, key, path, length, piece):
    """Sends `piece` every TICK_S until the server answers; (status, body, s)."""
    s = header(path, length)
    start = time.monotonic()
    s.settimeout(TICK_S)
    sent = 0
    status, body = 0, b''
    while sent + len(piece) < length:
        try:
            if s.recv(1, socket.MSG_PEEK): break  # the server has answered
        except socket.timeout:
            pass
        except OSError:
            break
        try:
            s.sendall(piece)
        except OSError:
            break
        sent += len(piece)
    s.settimeout(10)
    status, body = reply_of(s)
    results[key] = (status, body, time.monotonic() - start)


def slow_but_complete(results):
    body = json.dumps({'type': 'fields', 'pad': 'x' * 1960}).encode()
    s = header('/api/request', len(body))
    start = time.monotonic()
    for k in range(6):
        time.sleep(0.2)
        s.sendall(body[k * len(body) // 6:(k + 1) * len(body) // 6])
    status, reply = reply_of(s)
    results['complete'] = (status, reply, time.monotonic() - start)


def fast_upload(name):
    """(status, body) of a 60 MiB upload sent at once."""
    s = header('/api/upload?name=%s.lcmlog' % name, UPLOAD_BYTES)
    try:
        chunk = b'\0' * (1 << 20)
        for _ in range(UPLOAD_BYTES >> 20):
            s.sendall(chunk)
    except OSError:
        pass  # refused on its header
    return reply_of(s)


def user(stop, worst):
    """Health from another address and a page's evaluation, every TICK_S."""
    ws = WebSocket(port)
    n = 0
    while not stop.is_set():
        start = time.monotonic()
        try:
            s = socket.create_connection(('127.0.0.1', port), timeout=1, source_address=('127.0.0.2', 0))
            s.sendall(b'GET /api/health HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nConnection: close\r\n\r\n' % port)
            status, _ = reply_of(s)
        except OSError:
            status = 0
        n += 1
        reply = ws.ask({'id': n, 'type': 'evaluate', 'series': False,
                        'spec': {'plant': 'double_integrator', 'gains': [3.9, 0.06, 4.9]}})
        elapsed = time.monotonic() - start
        worst[0] = max(worst[0], elapsed)
        if status != 200 or reply.get('id') != n or 'iae' not in reply.get('result', {}) or elapsed > 1.0:
            fail('health %d and the evaluation %r in %.3f s while bodies trickle' % (status, str(reply)[:120], elapsed))
        time.sleep(TICK_S)
    worst[1] = n


results = {}
threads = [threading.Thread(target=trickle, args=(results, 'request %d' % k, '/api/request', 60000, b' '))
           for k in range(6)]
threads.append(threading.Thread(target=trickle, args=(results, 'upload', '/api/upload?name=slow.lcmlog',
                                                      UPLOAD_BYTES, b'\0' * 1024)))
threads.append(threading.Thread(target=slow_but_complete, args=(results,)))
stop, worst = threading.Event(), [0.0, 0]
watcher = threading.Thread(target=user, args=(stop, worst))
watcher.start()
for t in threads: t.start()
time.sleep(0.5)  # the trickling upload holds 60 MiB of the 64 MiB budget by now
status, body = fast_upload('second')
if status == 413 and b'MiB of uploads' in body:
    print('ok   a second 60 MiB upload while one trickles: 413 %s' % body.decode(), flush=True)
else:
    fail('a second 60 MiB upload while one trickles: %d %r' % (status, body[:200]))
for t in threads: t.join()
stop.set()
watcher.join()
for key in sorted(results):
    status, body, seconds = results[key]
    if key == 'complete':
        if status == 200 and b'"fields"' in body and seconds < DEADLINE_S:
            print('ok   a 2000-byte body sent in 6 parts over %.2f s: 200' % seconds, flush=True)
        else:
            fail('a 2000-byte body sent in 6 parts over %.2f s: %d %r' % (seconds, status, body[:200]))
        continue
    line = body.decode(errors='replace')
    if status == 408 and 'did not arrive within 2 s' in line and '\n' not in line.strip() and \
            DEADLINE_S - 0.1 <= seconds <= DEADLINE_S + 1.5:
        print('ok   %s trickling a %s every %.2f s: 408 after %.2f s, %s' % (
            key, 'KiB' if key == 'upload' else 'byte', TICK_S, seconds, line), flush=True)
    else:
        fail('%s trickling: %d after %.2f s, %r' % (key, status, seconds, body[:200]))
print('ok   /api/health and a WebSocket evaluation answered %d times meanwhile, slowest %.3f s' % (
    worst[1], worst[0]), flush=True)
status, body = fast_upload('after')
if status == 200:
    print('ok   once the trickling upload was cut, a 60 MiB upload is stored: %s' % body.decode(), flush=True)
else:
    fail('a 60 MiB upload after the trickling one was cut: %d %r' % (status, body[:200]))

for bad in ('0', '-1', '3601', 'nan', 'x'):
    run = subprocess.run([os.environ['PIDLAB_BIN'], 'serve', '--port', '0', '--body-timeout', bad],
                         capture_output=True, text=True, timeout=10)
    lines = run.stderr.strip().splitlines()
    if run.returncode == 2 and len(lines) == 1 and '--body-timeout' in lines[0]:
        print('ok   --body-timeout %s: exit 2, %s' % (bad, lines[0]), flush=True)
    else:
        fail('--body-timeout %s: exit %d, %r' % (bad, run.returncode, run.stderr[:300]))
sys.exit(1 if failures else 0)
