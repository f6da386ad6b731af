"""Hostile input against a running `pidlab serve` (tests/hostile/serve_hostile_test.sh):
seeded malformed HTTP requests and WebSocket frames, the server's health checked
every 500 cases. Prints one line per class and 'FAIL ...' on any failure."""
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
        return reply.split(b'\r\n', 1)[0]
    except (ConnectionError, socket.timeout, OSError):
        return b''


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
    kind = i % 6
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
print('ok   %d malformed HTTP requests' % http_cases, flush=True)
frames = 0
while frames < count - http_cases:
    frames += ws_case(rng.randint(1, 40))
    if frames // 500 != (frames - 1) // 500: healthy('%d hostile WebSocket frames' % frames)
print('ok   %d hostile WebSocket frames' % frames, flush=True)
healthy('everything')
print('%d cases in %.1f s, %d failures' % (http_cases + frames, time.time() - start, failures))
sys.exit(1 if failures else 0)
