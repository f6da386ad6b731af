"""Hostile input against a running `pidlab serve` (tests/hostile/serve_hostile_test.sh):
seeded malformed HTTP requests and WebSocket frames, the server's health checked
every 500 cases. A user's mistake must never be a 500: every HTTP reply read
is counted by status, and one class sends JSON objects of every request type
whose fields have the wrong JSON type ({"type": 5}, a spec that is an array,
an id that is an object). Prints one line per class and 'FAIL ...' on any
failure."""
import json, os, random, select, socket, struct, sys, threading, time
sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', 'cli'))
from serve_client import http, WebSocket

port, count, seed = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
rng = random.Random(seed)
failures = 0
VALID = (b'POST /api/request HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nContent-Type: application/json\r\n'
         b'Content-Length: %d\r\n\r\n')
SPEC = json.dumps({'type': 'evaluate', 'spec': {'plant': 'double_integrator', 'gains': [3.9, 0.06, 4.9]}}).encode()


fail_lock = threading.Lock()


def fail(msg):
    global failures
    with fail_lock:
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


def any_json(depth=0, rng=rng):
    """A random JSON value of any type."""
    k = rng.randrange(9 if depth < 3 else 6)
    if k == 0: return None
    if k == 1: return rng.choice([True, False])
    if k == 2: return rng.choice([0, -1, 5, 2 ** 63, -2 ** 70, 1e308, -0.0, 3.5])
    if k == 3: return rng.choice(['', 'x', 'evaluate', '\u0000', 'a' * 300, '../etc/passwd'])
    if k == 4: return []
    if k == 5: return {}
    if k == 6: return [any_json(depth + 1, rng) for _ in range(rng.randint(1, 3))]
    return {rng.choice(FIELDS + ['num', 'den', 'dt']): any_json(depth + 1, rng) for _ in range(rng.randint(1, 3))}


def typed_request(rng=rng):
    """A request object of a real type (or none), its fields of random JSON types."""
    r = {}
    if rng.random() < 0.9: r['type'] = rng.choice(TYPES) if rng.random() < 0.8 else any_json(0, rng)
    for _ in range(rng.randint(0, 4)): r[rng.choice(FIELDS)] = any_json(0, rng)
    return r


def mutate(data, rng=rng):
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


# Every WebSocket reply read: a reply is one JSON object, and an internal
# error (the server's "the server failed: ..." of an exception, its 500) is a
# failure as an HTTP 500 is. ws_replies counts them by kind.
ws_replies = {'answer': 0, 'error': 0, 'closed': 0, 'silent': 0}
ws_lock = threading.Lock()
SILENT_S = 3.0  # a reply takes milliseconds; no message for this long: the server is waiting
SENTINEL = json.dumps({'id': 'end of case'})  # answered 400 with its id: the replies before it are in


def ws_count(kind):
    with ws_lock:
        ws_replies[kind] += 1


def ws_reply(opcode, payload, sent):
    """Checks one message from the server; True for the sentinel's reply."""
    if opcode == 8: return False  # the close frame: read by ws_drain
    try:
        reply = json.loads(payload) if opcode == 1 else None
    except ValueError:
        reply = None
    if not isinstance(reply, dict):
        fail('a WebSocket reply that is not a JSON object (opcode %d): %r after %r' % (opcode, payload[:200], sent[-200:]))
        return False
    if reply.get('id') == 'end of case': return True
    error = reply.get('error')
    ws_count('error' if error is not None else 'answer')
    if isinstance(error, str) and error.startswith('the server failed'):
        fail('WebSocket internal error %r after %r' % (error[:200], sent[-200:]))
    return False


def ws_drain(ws, sent, wait):
    """Reads the server's messages: those waiting now, or (wait) until the
    sentinel's reply or the close. False once the connection has closed."""
    while True:
        try:
            if not wait and not select.select([ws.s], [], [], 0)[0]: return True
            ws.s.settimeout(SILENT_S)
            opcode, payload = ws.recv()
            if opcode == 8:
                ws_count('closed')
                return False
            if ws_reply(opcode, payload, sent) and wait: return True
        except socket.timeout:
            # A frame header the server still waits the rest of (random
            # bytes announcing a length): it neither answers nor closes.
            ws_count('silent')
            return False
        except (ConnectionError, OSError, EOFError):
            ws_count('closed')
            return False


def ws_frames(rng, frames):
    """`frames` hostile frames: half of them well-formed text messages that
    are not valid requests (request objects of every type with fields of
    random JSON types, mutated specs as UTF-8 text, deep nesting), answered
    one reply each; half protocol violations (random bytes, unmasked frames,
    bad opcodes, huge lengths, interleaved fragments), which close the
    connection."""
    for _ in range(frames):
        k = rng.randrange(16)
        if k < 5: yield ws_frame(json.dumps(typed_request(rng)).encode())
        elif k < 7: yield ws_frame(mutate(SPEC, rng).decode('utf-8', 'replace').encode())
        elif k == 7: yield ws_frame(b'[' * rng.randint(100, 60000))
        elif k == 8: yield ws_frame(bytes(rng.randrange(256) for _ in range(rng.randint(0, 200))))
        elif k == 9: yield ws_frame(mutate(SPEC, rng))
        elif k == 10: yield ws_frame(b'x', opcode=rng.choice([3, 4, 5, 6, 7, 11, 12, 13, 14, 15]))
        elif k == 11: yield ws_frame(SPEC, masked=False)
        elif k == 12: yield ws_frame(b'', length=rng.choice([2 ** 40, 2 ** 63 - 1, 70000]))
        elif k == 13: yield ws_frame(SPEC[:10], fin=False) + ws_frame(b'garbage', opcode=0, fin=rng.random() < 0.5)
        elif k == 14: yield ws_frame(b'{"type": "evaluate", "spec": ' + mutate(SPEC, rng) + b'}')
        else: yield bytes(rng.randrange(256) for _ in range(rng.randint(1, 64)))


def ws_case(rng, frames):
    """One connection, up to `frames` hostile frames until the server closes
    it, every reply read (those waiting after each frame, then all until the
    sentinel's reply or the server's close); the number sent (at least 1)."""
    try:
        ws = WebSocket(port)
    except (ConnectionError, socket.timeout, OSError) as e:
        fail('the WebSocket could not connect: %r' % e)
        return 0
    if ws.status != 101:
        fail('the WebSocket upgrade was refused: %d' % ws.status)
        return 0
    open_ = True
    sent, count = b'', 0
    try:
        for f in ws_frames(rng, frames):
            sent = f
            ws.s.settimeout(2)
            ws.s.sendall(f)
            count += 1
            open_ = ws_drain(ws, sent, wait=False)
            if not open_: break
        if open_:
            ws.s.settimeout(2)
            ws.send(SENTINEL)
            ws_drain(ws, sent, wait=True)
    except (ConnectionError, socket.timeout, OSError, EOFError):
        ws_count('closed')  # the server closed a connection it was right to close
    ws.s.close()
    return max(count, 1)


def ws_worker(index, frames_wanted, done):
    """One of WS_CLIENTS concurrent clients (as a page's tabs are), seeded of
    its own: connections of 1..40 frames until frames_wanted are sent."""
    rng_k = random.Random(seed * 1000 + index)
    frames = 0
    while frames < frames_wanted:
        frames += ws_case(rng_k, rng_k.randint(1, 40))
    done[index] = frames


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
WS_CLIENTS = 4
ws_wanted = count - http_cases
done = [0] * WS_CLIENTS
workers = [threading.Thread(target=ws_worker, args=(k, (ws_wanted + k) // WS_CLIENTS, done))
           for k in range(WS_CLIENTS)]
for w in workers: w.start()
# The server's health while the clients send, as a user's page asks it.
while any(w.is_alive() for w in workers):
    healthy('hostile WebSocket frames from %d clients at once' % WS_CLIENTS)
    for w in workers: w.join(timeout=0.5)
frames = sum(done)
print('ok   %d hostile WebSocket frames from %d concurrent clients; every reply read: %d answers, %d '
      'errors (none internal), %d connections closed by the server, %d left waiting for a frame\'s rest' % (
          frames, WS_CLIENTS, ws_replies['answer'], ws_replies['error'], ws_replies['closed'],
          ws_replies['silent']), flush=True)
if ws_replies['answer'] + ws_replies['error'] == 0:
    fail('no WebSocket reply was read')
healthy('everything')
print('%d cases in %.1f s, %d failures' % (http_cases + frames, time.time() - start, failures))
sys.exit(1 if failures else 0)
