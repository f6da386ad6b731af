"""Slow clients and deep JSON against a running `pidlab serve` on 127.0.0.1
(tests/hostile/serve_slow_test.sh): SLOW connections from 127.0.0.1 that each
send one byte of a request header every 2 s, reopened when the server closes
them (as an attacker would), far over the per-address cap; and 48 more, 16
from each of 127.0.0.3, .4 and .5, which fill the global cap with them.
Meanwhile /api/health and the page, asked from 127.0.0.2 (a user at an
address of its own), must answer within 1 s, CHECKS times. Then request bodies and WebSocket messages nested 30 000 deep
(under the 64 KiB bound: refused by the depth check, 400) and 100 000 deep
(over it: 413, and the WebSocket closed), /api/health answering after each.
Then 64 idle WebSockets and 64 slow bodies, 16 of each from every one of
127.0.1.1..4: /api/health answers within 1 s, 4 of 4 times. Prints 'ok ...'
lines, and 'FAIL ...' on any failure; runs at most about 2 * CHECKS + 20 s.
  serve_slow.py PORT SLOW CHECKS"""
import json, os, select, socket, struct, sys, threading, time
sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', 'cli'))
from serve_client import WebSocket

port, slow_count, checks = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
HEADER = b'GET / HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n\r\n' % port
failures = 0


def fail(msg):
    global failures
    failures += 1
    print('FAIL ' + msg, flush=True)


class Loris:
    """One slow connection from `source`: a header byte per tick; reopened
    once closed."""
    def __init__(self, source):
        self.source = source
        self.opened = 0
        self.closed_by_server = 0
        self.open()

    def open(self):
        self.s = socket.create_connection(('127.0.0.1', port), timeout=5, source_address=(self.source, 0))
        self.s.setblocking(False)
        self.sent = 0
        self.opened += 1

    def tick(self):
        r, _, _ = select.select([self.s], [], [], 0)
        alive = True
        if r:
            try:
                alive = self.s.recv(4096) != b''
            except OSError:
                alive = False
        if alive:
            try:
                self.s.send(HEADER[self.sent % (len(HEADER) - 2):][:1])  # never the header's end
                self.sent += 1
            except OSError:
                alive = False
        if not alive:
            self.closed_by_server += 1
            self.s.close()
            self.open()


def trickle(lorises, stop):
    while not stop.wait(2.0):
        for l in lorises:
            try:
                l.tick()
            except OSError as e:  # reopening refused or timed out: the server is not accepting
                fail('reopening a slow connection: %s' % e)
                return


def timed_get(path):
    """(status, seconds) of GET path on a fresh connection from 127.0.0.2, at
    most 1 s."""
    start = time.monotonic()
    try:
        s = socket.create_connection(('127.0.0.1', port), timeout=1.0, source_address=('127.0.0.2', 0))
        s.sendall(b'GET %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nConnection: close\r\n\r\n' % (path.encode(), port))
        data = b''
        while True:
            chunk = s.recv(65536)
            if not chunk: break
            data += chunk
            if time.monotonic() - start > 1.0: break
        s.close()
    except OSError:
        return 0, time.monotonic() - start
    elapsed = time.monotonic() - start
    head = data.split(b'\r\n', 1)[0].split(b' ')
    return (int(head[1]) if len(head) > 1 and head[1].isdigit() else 0), elapsed


def post(body, send_body=True):
    """(status, body) of POST /api/request with `body` (its header only
    unless send_body: the answer to a body over the bound comes first)."""
    s = socket.create_connection(('127.0.0.1', port), timeout=10)
    s.sendall(b'POST /api/request HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nContent-Type: application/json\r\n'
              b'Content-Length: %d\r\nConnection: close\r\n\r\n' % (port, len(body)) + (body if send_body else b''))
    data = b''
    while True:
        try:
            chunk = s.recv(65536)
        except ConnectionResetError:
            break
        if not chunk: break
        data += chunk
    s.close()
    head, _, rest = data.partition(b'\r\n\r\n')
    return int(head.split(b' ')[1]), rest


def deep(depth):
    return b'{"a":' + b'[' * (depth - 1) + b']' * (depth - 1) + b'}'


def health_after(what):
    status, seconds = timed_get('/api/health')
    if status == 200 and seconds <= 1.0:
        print('ok   /api/health answers 200 after %s (%.3f s)' % (what, seconds), flush=True)
    else:
        fail('/api/health after %s: status %d in %.3f s' % (what, status, seconds))


# (a) The slow connections, opened at once and trickling.
lorises = [Loris('127.0.0.1') for _ in range(slow_count)]
lorises += [Loris('127.0.0.%d' % (3 + i // 16)) for i in range(48)]
stop = threading.Event()
thread = threading.Thread(target=trickle, args=(lorises, stop), daemon=True)
thread.start()

# (b) Health and the page, CHECKS times each, while they trickle.
worst = 0.0
for i in range(checks):
    time.sleep(1.0)
    for path, needle in (('/api/health', 200), ('/', 200)):
        status, seconds = timed_get(path)
        worst = max(worst, seconds)
        if status != needle or seconds > 1.0:
            fail('GET %s with %d + 48 slow connections: status %d in %.3f s (check %d)' % (path, slow_count, status,
                                                                                      seconds, i + 1))
stop.set()
thread.join()
opened = sum(l.opened for l in lorises)
closed = sum(l.closed_by_server for l in lorises)
print('ok   %d checks of /api/health and / with %d + 48 slow connections trickling: slowest %.3f s; the '
      'server closed %d of %d slow connections it accepted' % (checks, slow_count, worst, closed, opened), flush=True)
if closed == 0:
    fail('the server closed none of %d slow connections: they hold every slot' % opened)
for l in lorises:
    l.s.close()

# (b2) 64 idle WebSockets that never read (so never answer a ping) and 64
# POSTs whose bodies trickle a byte every 2 s, 16 of each from every one of
# 127.0.1.1..4 (past the per-address cap of 16 without ever reaching it), each
# reopened once the server closes it: /api/health from 127.0.0.2 still
# answers within 1 s, CHECKS_IDLE times.
class Idler:
    """A WebSocket that never reads, or a POST whose body never ends, from
    `source`; reopened once closed."""
    def __init__(self, source, kind):
        self.source, self.kind = source, kind
        self.opened = self.closed_by_server = 0
        self.open()

    def open(self):
        self.s = socket.create_connection(('127.0.0.1', port), timeout=5, source_address=(self.source, 0))
        if self.kind == 'ws':
            self.s.sendall(b'GET /ws HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n'
                           b'Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n' % port)
        else:
            self.s.sendall(b'POST /api/request HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nContent-Type: application/json\r\n'
                           b'Content-Length: 60000\r\n\r\n{' % port)
        self.s.setblocking(False)
        self.opened += 1

    def tick(self):
        alive = True
        try:
            r, _, _ = select.select([self.s], [], [], 0)
            # Read and dropped: the handshake's reply and the server's pings,
            # never answered.
            if r: alive = self.s.recv(65536) != b''
            if alive and self.kind == 'body': self.s.send(b' ')
        except OSError:
            alive = False
        if not alive:
            self.closed_by_server += 1
            self.s.close()
            self.open()


def hold(idlers, stop):
    while not stop.wait(2.0):
        for x in idlers:
            try:
                x.tick()
            except OSError as e:
                fail('reopening an idle connection: %s' % e)
                return


checks_idle = 4
idlers = [Idler('127.0.1.%d' % (1 + i % 4), kind) for kind in ('ws', 'body') for i in range(64)]
stop = threading.Event()
thread = threading.Thread(target=hold, args=(idlers, stop), daemon=True)
thread.start()
worst = 0.0
for i in range(checks_idle):
    time.sleep(1.0)
    status, seconds = timed_get('/api/health')
    worst = max(worst, seconds)
    if status != 200 or seconds > 1.0:
        fail('GET /api/health with 64 idle WebSockets and 64 slow bodies from 127.0.1.1-4: status %d in '
             '%.3f s (check %d)' % (status, seconds, i + 1))
stop.set()
thread.join()
opened = sum(x.opened for x in idlers)
closed = sum(x.closed_by_server for x in idlers)
print('ok   %d checks of /api/health with 64 idle WebSockets and 64 slow bodies from 127.0.1.1-4: slowest '
      '%.3f s; the server closed %d of the %d it accepted' % (checks_idle, worst, closed, opened), flush=True)
if closed == 0:
    fail('the server closed none of %d idle connections: they hold every slot' % opened)
for x in idlers:
    x.s.close()

# (c) Deep nesting, as the request body and as a WebSocket message.
status, body = post(deep(30000))
if status == 400 and b'nested deeper than 64 levels' in body:
    print('ok   a body nested 30000 deep gets 400: %s' % body.decode(), flush=True)
else:
    fail('a body nested 30000 deep: status %d, %r' % (status, body[:200]))
health_after('a body nested 30000 deep')
status, body = post(deep(100000), send_body=False)
if status == 413:
    print('ok   a body nested 100000 deep (%d bytes) gets 413: %s' % (len(deep(100000)), body.decode()), flush=True)
else:
    fail('a body nested 100000 deep: status %d, %r' % (status, body[:200]))
health_after('a body nested 100000 deep')

ws = WebSocket(port)
reply = ws.ask({'id': 1, 'type': 'fields'})
if reply.get('type') != 'fields' or reply.get('id') != 1:
    fail('the WebSocket does not answer a fields request: %r' % str(reply)[:200])
ws.send(deep(30000).decode())
opcode, payload = ws.recv()
reply = json.loads(payload) if opcode == 1 else {}
if 'nested deeper than 64 levels' in reply.get('error', ''):
    print('ok   a WebSocket message nested 30000 deep gets its error: %s' % reply['error'], flush=True)
else:
    fail('a WebSocket message nested 30000 deep: opcode %d, %r' % (opcode, payload[:200]))
reply = ws.ask({'id': 2, 'type': 'fields'})
if reply.get('id') != 2:
    fail('the WebSocket stopped answering after the deep message: %r' % str(reply)[:200])
# Its frame header only: the server closes on the length it announces.
ws.s.sendall(bytes([0x81, 0x80 | 127]) + struct.pack('>Q', len(deep(100000))) + os.urandom(4))
try:
    opcode, payload = ws.recv()
    code = int.from_bytes(payload[:2], 'big') if opcode == 8 else 0
except (EOFError, OSError):
    opcode, code = 8, 0
if opcode == 8 and code in (0, 1009):
    print('ok   a WebSocket message nested 100000 deep closes the WebSocket (code %d)' % code, flush=True)
else:
    fail('a WebSocket message nested 100000 deep: opcode %d' % opcode)
health_after('the deep WebSocket messages')
sys.exit(1 if failures else 0)
