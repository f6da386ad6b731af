"""Concurrent large uploads against a running `pidlab serve --log-dir`
(tests/hostile/serve_hostile_test.sh, which exports PIDLAB_SERVER_PID): 8
clients each POST a 60 MiB body to /api/upload at once. The request bodies
the server holds in memory are bounded in total, so its peak RSS (VmHWM of
/proc/PID/status) must stay under 200 MB; every upload gets 200 or 413 with
one line, at least one is stored, and once they are done a ninth 60 MiB
upload alone is stored (the budget was given back). COUNT and SEED are
taken, as serve_hostile_test.sh passes them, and ignored.
  serve_uploads.py PORT COUNT SEED"""
import json, os, socket, sys, threading

port = int(sys.argv[1])
pid = int(os.environ['PIDLAB_SERVER_PID'])
UPLOADS, BODY_BYTES, LIMIT_BYTES = 8, 60 << 20, 200 * 1000 * 1000
CHUNK = b'\0' * (1 << 20)
failures = 0


def fail(msg):
    global failures
    failures += 1
    print('FAIL ' + msg, flush=True)


def status_kb(field):
    for line in open('/proc/%d/status' % pid):
        if line.startswith(field + ':'):
            return int(line.split()[1])
    return 0


def upload(results, i):
    """POSTs 60 MiB; (status, reply body) into results[i]."""
    try:
        s = socket.create_connection(('127.0.0.1', port), timeout=60)
        s.sendall(b'POST /api/upload?name=big%d.lcmlog HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n'
                  b'Content-Length: %d\r\nConnection: close\r\n\r\n' % (i, port, BODY_BYTES))
        try:
            for _ in range(BODY_BYTES // len(CHUNK)):
                s.sendall(CHUNK)
        except OSError:
            pass  # refused on its header: the server closed before the body
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
        results[i] = (int(parts[1]) if len(parts) > 1 and parts[1].isdigit() else 0, body)
    except OSError as e:
        results[i] = (0, str(e).encode())


start_kb = status_kb('VmRSS')
results = [None] * UPLOADS
threads = [threading.Thread(target=upload, args=(results, i)) for i in range(UPLOADS)]
for t in threads: t.start()
for t in threads: t.join()
peak_kb = status_kb('VmHWM')
codes = [r[0] for r in results]
stored = codes.count(200)
for status, body in results:
    if status not in (200, 413):
        fail('an upload got %d: %r' % (status, body[:200]))
    elif status == 413 and (b'\n' in body.strip() or b'MiB of uploads' not in body):
        fail('a refused upload does not say why in one line: %r' % body[:200])
if stored < 1:
    fail('none of %d concurrent uploads was stored: %s' % (UPLOADS, codes))
alone = [None]
upload(alone, 0)
if alone[0][0] != 200:
    fail('a 60 MiB upload alone after the others got %d: %r' % (alone[0][0], alone[0][1][:200]))
peak_kb = max(peak_kb, status_kb('VmHWM'))
print('%s  %d concurrent uploads of 60 MiB: %d stored, %d refused with 413 (%s); then one alone: %d; '
      'server RSS %.0f MB before, peak %.0f MB (limit %.0f MB)' %
      ('ok  ' if peak_kb * 1024 < LIMIT_BYTES else 'FAIL', UPLOADS, stored, codes.count(413),
       json.loads(next((r[1] for r in results if r[0] == 413), b'{"error": ""}') or b'{}').get('error', ''),
       alone[0][0], start_kb * 1.024e-3, peak_kb * 1.024e-3, LIMIT_BYTES / 1e6), flush=True)
if peak_kb * 1024 >= LIMIT_BYTES: failures += 1
sys.exit(1 if failures else 0)
