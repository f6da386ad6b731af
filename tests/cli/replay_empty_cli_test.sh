#!/usr/bin/env bash
# Empty means empty (docs/logs.md, docs/security.md): `pidlab replay` on a
# 0-byte file or a file with no LCM event exits 1 with one line naming the
# file and "no LCM event", with and without --json; a path that cannot be
# opened stays exit 2; a log whose one event is on another channel is still a
# log (exit 0). `pidlab serve`, in a private network namespace of its own on
# 127.0.0.1, answers 400 to opening such a file and to uploading 0 bytes.
set -uo pipefail
if [[ $# -ne 1 ]]; then
  echo "usage: $0 PIDLAB_BINARY" >&2
  exit 2
fi
pidlab=$(realpath -- "$1")
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
ip link set lo up || { echo "FAIL: cannot bring up the private namespace's loopback"; exit 1; }
here=$(cd "$(dirname -- "$0")" && pwd)
source "$here/stderr_shape.sh"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); server=; trap 'kill $server 2>/dev/null; rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
mkdir logs
: > logs/empty.lcmlog
printf 'this is not an LCM log\n' > logs/text.lcmlog
# One lcm-logger event (sync word, eventnum, utime, channel and data lengths) on a foreign channel.
/usr/bin/python3 -c '
import struct, sys
channel, data = b"SOMEONE_ELSE", b"hello"
sys.stdout.buffer.write(struct.pack(">IqqII", 0xEDA1DA01, 0, 1700000000000000, len(channel), len(data)) + channel + data)
' > logs/foreign.lcmlog

for file in empty text; do
  for json in "" "--json"; do
    "$pidlab" replay "logs/$file.lcmlog" $json > out 2> err
    status=$?
    check "replay $json of the $(stat -c %s logs/$file.lcmlog)-byte $file.lcmlog exits 1 with one line naming it" \
      "[ $status -eq 1 ] && [ ! -s out ] && only_line_ok err 'logs/$file.lcmlog' && grep -q 'no LCM event' err"
  done
done
"$pidlab" replay logs/missing.lcmlog > out 2> err
check "replay of a missing file exits 2" "[ $? -eq 2 ] && only_line_ok err 'logs/missing.lcmlog'"
"$pidlab" replay logs/foreign.lcmlog > out 2> err
check "replay of a log whose one event is foreign exits 0 with no episode" \
  "[ $? -eq 0 ] && grep -q '^log logs/foreign.lcmlog: 1 events' out && grep -q '(no episode in the log)' out"

"$pidlab" serve --port 0 --log-dir logs > serve.out 2> serve.err &
server=$!
for _ in $(seq 200); do grep -q '^pidlab serve: http' serve.out && break; sleep 0.05; done
port=$(sed -nE 's#^pidlab serve: http://127\.0\.0\.1:([0-9]+)/$#\1#p' serve.out)
check "serve --log-dir logs starts on 127.0.0.1" "[ -n '$port' ]"
PYTHONPATH="$here" /usr/bin/python3 - "$port" <<'PY'
import json, sys
from serve_client import http, WebSocket
port = int(sys.argv[1])
def check(name, ok, got):
    print(('ok   ' if ok else 'FAIL ') + name + ('' if ok else ': ' + repr(got)[:300]))
ws = WebSocket(port)
for name in ('empty.lcmlog', 'text.lcmlog'):
    r = ws.ask({'type': 'log_open', 'path': name})
    check('log_open of %s answers with no LCM event' % name, 'no LCM event' in r.get('error', '') and name in r['error'], r)
r = ws.ask({'type': 'log_open', 'path': 'foreign.lcmlog'})
check('log_open of foreign.lcmlog opens a log of 0 episodes', r.get('type') == 'log' and not r.get('episodes'), r)
status, body = http(port, 'POST', '/api/upload?name=empty.lcmlog', b'')
check('an upload of 0 bytes answers 400 with no LCM event', status == 400 and b'no LCM event' in body, (status, body))
status, body = http(port, 'POST', '/api/upload?name=text.lcmlog', b'this is not an LCM log\n')
log_id = json.loads(body).get('log_id') if status == 200 else None
r = ws.ask({'type': 'log_open', 'log_id': log_id})
check('an uploaded file of no LCM event is stored, and opening it answers no LCM event',
      status == 200 and 'no LCM event' in r.get('error', ''), (status, body, r))
PY
kill -TERM "$server"; wait "$server"
check "the server stopped with status 0" "[ $? -eq 0 ]"
server=
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
