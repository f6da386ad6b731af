"""A stdlib-only client of `pidlab serve` for tests/cli/serve_cli_test.sh:
HTTP requests and a minimal WebSocket (RFC 6455: the handshake, masked text
frames out, unmasked frames in)."""
import base64, json, os, socket, struct, sys


def http(port, method, path, body=b'', headers=None, raw=None):
    """(status, body bytes) of one request on a fresh connection."""
    s = socket.create_connection(('127.0.0.1', port), timeout=20)
    if raw is None:
        h = {'Host': '127.0.0.1:%d' % port, 'Content-Length': str(len(body)), 'Connection': 'close'}
        h.update(headers or {})
        raw = ('%s %s HTTP/1.1\r\n' % (method, path) + ''.join('%s: %s\r\n' % kv for kv in h.items()) +
               '\r\n').encode() + body
    s.sendall(raw)
    data = b''
    while True:
        chunk = s.recv(65536)
        if not chunk: break
        data += chunk
    s.close()
    head, _, rest = data.partition(b'\r\n\r\n')
    return int(head.split(b' ')[1]), rest


class WebSocket:
    def __init__(self, port, path='/ws', origin=None):
        self.s = socket.create_connection(('127.0.0.1', port), timeout=20)
        key = base64.b64encode(os.urandom(16)).decode()
        lines = ['GET %s HTTP/1.1' % path, 'Host: 127.0.0.1:%d' % port, 'Upgrade: websocket',
                 'Connection: Upgrade', 'Sec-WebSocket-Key: ' + key, 'Sec-WebSocket-Version: 13']
        if origin: lines.append('Origin: ' + origin)
        self.s.sendall(('\r\n'.join(lines) + '\r\n\r\n').encode())
        head = b''
        while b'\r\n\r\n' not in head:
            chunk = self.s.recv(1)
            if not chunk: break
            head += chunk
        self.status = int(head.split(b' ')[1]) if head else 0

    def send(self, text, opcode=1):
        payload = text.encode() if isinstance(text, str) else text
        mask = os.urandom(4)
        n = len(payload)
        header = bytes([0x80 | opcode])
        if n < 126: header += bytes([0x80 | n])
        elif n < 65536: header += bytes([0x80 | 126]) + struct.pack('>H', n)
        else: header += bytes([0x80 | 127]) + struct.pack('>Q', n)
        self.s.sendall(header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload)))

    def _exact(self, n):
        data = b''
        while len(data) < n:
            chunk = self.s.recv(n - len(data))
            if not chunk: raise EOFError('closed')
            data += chunk
        return data

    def recv(self):
        """(opcode, payload) of the next message, its fragments joined, or
        (8, code and reason) of a close frame. A ping is answered with its pong, as a browser does (the server closes a
        WebSocket that stays silent through its ping), and not returned."""
        opcode, payload = None, b''
        while True:
            b0, b1 = self._exact(2)
            n = b1 & 0x7f
            if n == 126: n = struct.unpack('>H', self._exact(2))[0]
            elif n == 127: n = struct.unpack('>Q', self._exact(8))[0]
            data = self._exact(n)
            if b0 & 0x0f == 9:
                self.send(data, opcode=10)
                continue
            if b0 & 0x0f == 10: continue
            # A close, even amid a message's fragments (the server closing on
            # a protocol error abandons the message it was sending).
            if b0 & 0x0f == 8: return 8, data
            if opcode is None: opcode = b0 & 0x0f
            payload += data
            if b0 & 0x80: return opcode, payload

    def ask(self, obj):
        self.send(json.dumps(obj))
        op, payload = self.recv()
        assert op == 1, op
        return json.loads(payload)
