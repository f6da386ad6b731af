"""Hostile input against a running `pidlab serve` (tests/hostile/serve_hostile_test.sh):
seeded malformed HTTP requests and WebSocket frames, the server's health checked
every 500 cases. A user's mistake must never be a 500: every HTTP reply read
is counted by status, and one class sends JSON objects of every request type
whose fields have the wrong JSON type ({"type": 5}, a spec that is an array,
an id that is an object). Prints one line per class and 'FAIL ...' on any
failure."""
import json, os, random, socket, struct, sys, time
sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', 'cli'))
from serve_client import http, WebSocket

port, count, seed = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
rng = random.Random(seed)
failures = 0
VALID = (b'POST /api/request HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nContent-Type: application/json\r\n'
         b'Content-Length: %d\r\n\r\n')
SPEC = json.dumps({'type': 'evaluate', 'spec': {'plant': 'double_integrator', 'gains': [3.9, 0.06, 4.9]}}).encode()


def fail(msg):
    global failures
    failures += 1
    print('FAIL ' + msg, flush=True)


def raw(data, read=True):
    """Sends bytes on a fresh connection; the reply's first line, or ''."""
    try:
        s = socket.create_connection(('127.0.0.1', port), timeout=10)
        s.sendall(data)
        s.shutdown(socket.SHUT_WR)
        reply = b''
        while read:
            chunk = s.recv(65536)
            if not chunk: break
            reply += chunk
        s.close()
        line = reply.split(b'\r\n', 1)[0]
        parts = line.split(b' ')
        if len(parts) > 1 and parts[1].isdigit():
            statuses[int(parts[1])] = statuses.get(int(parts[1]), 0) + 1
            if parts[1].startswith(b'5'):
                fail('HTTP %s for %r: %r' % (parts[1].decode(), data[:200], reply.split(b'\r\n\r\n', 1)[-1][:200]))
        return line
    except (ConnectionError, socket.timeout, OSError):
        return b''


statuses = {}
TYPES = ['evaluate', 'fields', 'paper_designs', 'export', 'pil_cost', 'tune', 'tune_cancel', 'identify',
         'identify_cancel', 'log_open', 'log_episode', 'server_info', 'live_subscribe', 'live_unsubscribe',
         'live_select', 'live_data', 'run_on_trio']
FIELDS = ['type', 'spec', 'series', 'id', 'force', 'log_id', 'path', 'index', 'upload_id', 'model', 'name',
          'episode', 'options', 'gains', 'plant', 'monte_carlo']


def any_json(depth=0):
    """A random JSON value of any type."""
    k = rng.randrange(9 if depth < 3 else 6)
    if k == 0: return None
    if k == 1: return rng.choice([True, False])
    if k == 2: return rng.choice([0, -1, 5, 2 ** 63, -2 ** 70, 1e308, -0.0, 3.5])
    if k == 3: return rng.choice(['', 'x', 'evaluate', '\u0000', 'a' * 300, '../etc/passwd'])
    if k == 4: return []
    if k == 5: return {}
    if k == 6: return [any_json(depth + 1) for _ in range(rng.randint(1, 3))]
    return {rng.choice(FIELDS + ['num', 'den', 'dt']): any_json(depth + 1) for _ in range(rng.randint(1, 3))}


def typed_request():
    """A request object of a real type (or none), its fields of random JSON types."""
    r = {}
    if rng.random() < 0.9: r['type'] = rng.choice(TYPES) if rng.random() < 0.8 else any_json()
    for _ in range(rng.randint(0, 4)): r[rng.choice(FIELDS)] = any_json()
    return r


def mutate(data):
    b = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        op = rng.randrange(4)
        i = rng.randrange(len(b) + 1)
        if op == 0 and b: b[min(i, len(b) - 1)] = rng.randrange(256)
        elif op == 1: b[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 16)))
        elif op == 2 and b: del b[i:i + rng.randint(1, 16)]
        else: b[i:i] = rng.choice([b'\r\n', b'\r\n\r\n', b':', b'\x00', b'%', b'?token=', b'Content-Length: 99999999\r\n',
                                   b'Transfer-Encoding: chunked\r\n', b'Upgrade: websocket\r\n'])
    return bytes(b)


def http_case(i):
    kind = i % 7
    if kind == 6:
        body = json.dumps(typed_request()).encode()
        raw(VALID % (port, len(body)) + body)
        return
    if kind == 0:
        data = bytes(rng.randrange(256) for _ in range(rng.randint(1, 2048)))
    elif kind == 1:
        data = mutate(VALID % (port, len(SPEC)) + SPEC)
    elif kind == 2:
        body = mutate(SPEC)
        data = VALID % (port, len(body)) + body
    elif kind == 3:
        data = b'GET /' + b'a' * rng.randint(1, 20000) + b' HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n\r\n' % port
    elif kind == 4:
        data = (b'POST /api/request HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nTransfer-Encoding: chunked\r\n\r\n' % port +
                bytes(rng.choice(b'0123456789abcdefxyz\r\n;') for _ in range(rng.randint(1, 300))))
    else:
        body = json.dumps(rng.choice([[], 1, 'x', None, {'type': 'evaluate'}, {'type': 'evaluate', 'spec': []},
                                      {'type': 'evaluate', 'spec': {'gains': 'a'}}, {'type': 7},
                                      {'type': 'evaluate', 'spec': {'plant': 'custom', 'num': [1], 'den': [0]}},
                                      {'type': 'evaluate', 'spec': {'plant': 'double_integrator', 'gains': [1e308, 1e308, 1e308]}}]))
        body = body.encode() if rng.random() < 0.5 else b'[' * rng.randint(1000, 60000)
        data = VALID % (port, len(body)) + body
    raw(data, read=rng.random() < 0.8)


def ws_frame(payload, opcode=1, masked=True, fin=True, length=None):
    n = len(payload) if length is None else length
    head = bytes([(0x80 if fin else 0) | opcode])
    mbit = 0x80 if masked else 0
    if n < 126: head += bytes([mbit | n])
    elif n < 65536: head += bytes([mbit | 126]) + struct.pack('>H', n)
    else: head += bytes([mbit | 127]) + struct.pack('>Q', n)
    if not masked: return head + payload
    mask = os.urandom(4)
    return head + mask + bytes(b ^ mask[j % 4] for j, b in enumerate(payload))


def ws_case(frames):
    """One connection, `frames` hostile frames; the number sent."""
    try:
        ws = WebSocket(port)
        if ws.status != 101:
            fail('the WebSocket upgrade was refused: %d' % ws.status)
            return 0
        ws.s.settimeout(2)
        for _ in range(frames):
            k = rng.randrange(8)
            if k == 0: f = ws_frame(bytes(rng.randrange(256) for _ in range(rng.randint(0, 200))))
            elif k == 1: f = ws_frame(mutate(SPEC))
            elif k == 2: f = ws_frame(b'x', opcode=rng.choice([3, 4, 5, 6, 7, 11, 12, 13, 14, 15]))
            elif k == 3: f = ws_frame(SPEC, masked=False)
            elif k == 4: f = ws_frame(b'', length=rng.choice([2 ** 40, 2 ** 63 - 1, 70000]))
            elif k == 5: f = ws_frame(b'[' * rng.randint(100, 60000))
            elif k == 6: f = ws_frame(SPEC[:10], fin=False) + ws_frame(b'garbage', opcode=0, fin=rng.random() < 0.5)
            else: f = bytes(rng.randrange(256) for _ in range(rng.randint(1, 64)))
            ws.s.sendall(f)
        ws.s.close()
    except (ConnectionError, socket.timeout, OSError, EOFError):
        pass  # the server closed a connection it was right to close
    return frames


def healthy(where):
    try:
        status, body = http(port, 'POST', '/api/request', SPEC)
        if status != 200 or b'"iae"' not in body:
            fail('after %s the server answered %d %r' % (where, status, body[:100]))
    except Exception as e:  # noqa: BLE001
        fail('after %s the server did not answer: %r' % (where, e))


start = time.time()
http_cases = count // 2
for i in range(http_cases):
    http_case(i)
    if (i + 1) % 500 == 0: healthy('%d malformed HTTP requests' % (i + 1))
print('ok   %d malformed HTTP requests; replies read by status: %s' % (
    http_cases, ', '.join('%d: %d' % kv for kv in sorted(statuses.items()))), flush=True)
if sum(n for code, n in statuses.items() if code >= 500):
    fail('%d of the replies were 5xx' % sum(n for code, n in statuses.items() if code >= 500))
frames = 0
while frames < count - http_cases:
    frames += ws_case(rng.randint(1, 40))
    if frames // 500 != (frames - 1) // 500: healthy('%d hostile WebSocket frames' % frames)
print('ok   %d hostile WebSocket frames' % frames, flush=True)
healthy('everything')
print('%d cases in %.1f s, %d failures' % (http_cases + frames, time.time() - start, failures))
sys.exit(1 if failures else 0)
