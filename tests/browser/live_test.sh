#!/usr/bin/env bash
# browser.live_trio: the Live and Logs tabs of `pidlab serve --lcm-url` in
# Debian's headless Chromium (tests/browser/live_test.js), in a private network
# namespace with multicast over its loopback: a 25 s episode at dt = 1 ms run
# by `pidlab launch --log` is watched (final y, u, n bit for bit with the log),
# "Run on the trio" agrees bit for bit, a --realtime episode's deadline
# statistics equal evaluate --json's, the log is opened, uploaded and scrubbed
# (#log-iae equals pidlab replay --json), a copy cut mid-event is shown as
# pidlab replay --json reads it; the Live tab's screenshot goes to
# OUT_DIR/live.png (docs/live.png is a copy of one, made by hand: a test
# leaves the source tree as it found it).
#   live_test.sh PIDLAB_BINARY SOURCE_DIR OUT_DIR [logs]
# With "logs" only the Logs tab's part runs (a server without --lcm-url).
set -uo pipefail
if [[ $# -lt 3 || $# -gt 4 ]]; then
  echo "usage: $0 PIDLAB_BINARY SOURCE_DIR OUT_DIR [logs]" >&2
  exit 2
fi
pidlab=$(realpath -- "$1") source_dir=$(realpath -- "$2") out_dir=$(realpath -m -- "$3") parts=${4:-all}
source "$(dirname -- "${BASH_SOURCE[0]}")/require_browser.sh" "$source_dir" || exit 1
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
{ ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo; } ||
  { echo "FAIL: cannot set up the private namespace's loopback with multicast"; exit 1; }
export PATH="$(dirname "$pidlab"):$PATH"  # the trio's binaries beside pidlab
mkdir -p "$out_dir" && rm -f "$out_dir"/live*.png "$out_dir"/logs.png
tmp=$(mktemp -d)
server=
trap '[ -n "$server" ] && kill "$server" 2>/dev/null; rm -rf "$tmp"' EXIT
lcm_url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
live_flags=()
[ "$parts" = all ] && live_flags=(--lcm-url "$lcm_url")
# docs/workbench.md's example, as written (port 8080 is free in this namespace),
# answering over HTTP; then the two flags' bad values (exit 2, one line).
mkdir "$tmp/doc" "$tmp/doc/logs"
cp "$source_dir/tests/browser/live_test.sh" "$tmp/doc/logs/not-a-log.lcmlog"
(cd "$tmp/doc" && exec "$pidlab" serve --log-dir logs --max-upload-mb 16) > "$tmp/doc/serve.out" 2>&1 &
doc_server=$!
deadline=$((SECONDS + 10))
until grep -q '^pidlab serve: http' "$tmp/doc/serve.out" || ((SECONDS > deadline)); do sleep 0.05; done
reply=$(curl -s --data-binary '{"type":"log_open","path":"not-a-log.lcmlog"}' http://127.0.0.1:8080/api/request)
kill "$doc_server"; wait "$doc_server" 2>/dev/null
if ! grep -qx 'pidlab serve: http://127.0.0.1:8080/' "$tmp/doc/serve.out" || [[ $reply != *"is not an LCM log"* && $reply != *"not-a-log.lcmlog"* ]]; then
  echo "FAIL: pidlab serve --log-dir logs --max-upload-mb 16: $(head -c 200 "$tmp/doc/serve.out") / $reply"
  exit 1
fi
echo "ok   pidlab serve --log-dir logs --max-upload-mb 16: $reply"
for bad in "--max-upload-mb 0" "--log-dir $tmp/missing"; do
  # shellcheck disable=SC2086
  "$pidlab" serve --port 0 $bad > "$tmp/bad.out" 2>&1 && code=0 || code=$?
  if [[ $code != 2 || $(wc -l < "$tmp/bad.out") != 1 ]]; then
    echo "FAIL: pidlab serve $bad: exit $code, $(head -c 200 "$tmp/bad.out")"; exit 1
  fi
  echo "ok   pidlab serve $bad: exit 2, $(cat "$tmp/bad.out")"
done
mkdir "$tmp/server-tmp"  # the server's TMPDIR: its uploads' directory is made there
TMPDIR="$tmp/server-tmp" "$pidlab" serve --port 0 --bind 127.0.0.1 --log-dir "$tmp" --max-upload-mb 16 "${live_flags[@]}" \
  > "$tmp/serve.out" 2> "$tmp/serve.err" &
server=$!
deadline=$((SECONDS + 10))
until grep -q '^pidlab serve: http' "$tmp/serve.out" || ((SECONDS > deadline)); do sleep 0.05; done
url=$(sed -n 's/^pidlab serve: //p' "$tmp/serve.out" | head -1)
if [[ ! $url =~ ^http://127\.0\.0\.1:[0-9]+/ ]]; then
  echo "FAIL: pidlab serve --port 0 printed no URL on 127.0.0.1: $(head -c 300 "$tmp/serve.out" "$tmp/serve.err")"
  exit 1
fi
base=${url%/}
# The upload limit, on the headers alone: 413 above --max-upload-mb, naming the limit.
code=$(head -c $((17 * 1024 * 1024)) /dev/zero | curl -s -o "$tmp/413.json" -w '%{http_code}' \
  -H 'Content-Type: application/octet-stream' --data-binary @- "$base/api/upload?name=big.lcmlog")
if [[ $code != 413 ]] || ! grep -q "limit of 16777216 bytes" "$tmp/413.json"; then
  echo "FAIL: a 17 MiB upload with --max-upload-mb 16: HTTP $code $(head -c 200 "$tmp/413.json")"
  exit 1
fi
echo "ok   a 17 MiB upload with --max-upload-mb 16 is refused: 413 $(cat "$tmp/413.json")"
# The token, Host and Origin rules of /api/request, on the upload's headers.
for header in "Origin: http://evil.example" "Host: evil.example:80"; do
  code=$(curl -s -o "$tmp/refused.json" -w '%{http_code}' -H "$header" --data-binary 'x' "$base/api/upload?name=a.lcmlog")
  if [[ $code != 403 ]]; then echo "FAIL: an upload with '$header': HTTP $code"; exit 1; fi
  echo "ok   an upload with '$header': 403 $(cat "$tmp/refused.json")"
done
code=$(curl -s -o "$tmp/bad.json" -w '%{http_code}' --data-binary 'x' "$base/api/upload?name=../x")
if [[ $code != 400 ]]; then echo "FAIL: upload name ../x: HTTP $code"; exit 1; fi
echo "ok   upload name ../x: 400 $(cat "$tmp/bad.json")"
timeout 200 node "$source_dir/tests/browser/live_test.js" \
  --url "$url" --pidlab "$pidlab" --modules "$source_dir/node_modules" --chromium "$chromium" \
  --out "$out_dir" --tmp "$tmp" --lcm-url "$lcm_url" --parts "$parts"
status=$?
[ $status -eq 124 ] && echo "FAIL: the browser test did not finish in 200 s"
# Random bytes through the upload are one line of 400 and the server keeps
# serving (the reader is pidlab replay's: tests/hostile). A log cut mid-event
# is the page's own step (live_test.js): what it shows of the cut equals what
# pidlab replay --json reads of the same file.
if ((status == 0)); then
  ask() { curl -s -w ' %{http_code}' --data-binary "$1" "$base/api/request"; }
  head -c 4096 /dev/urandom > "$tmp/noise.lcmlog"
  noise_id=$(curl -s --data-binary @"$tmp/noise.lcmlog" "$base/api/upload?name=noise.lcmlog" | sed -n 's/.*"log_id":"\([^"]*\)".*/\1/p')
  noise=$(ask '{"type":"log_open","log_id":"'"$noise_id"'"}')
  if [[ $noise != *' 400' ]]; then
    echo "FAIL: damaged uploads: random bytes $noise"
    status=1
  else
    echo "ok   damaged uploads: random bytes: $noise"
  fi
fi
kill -0 "$server" 2>/dev/null || { echo "FAIL: pidlab serve is no longer running"; status=1; }
# The uploads' directory goes with the server.
made=$(ls "$tmp/server-tmp" | wc -l)
kill "$server"; wait "$server" 2>/dev/null; server=
if ((made != 1)) || [ -n "$(ls "$tmp/server-tmp")" ]; then
  echo "FAIL: the uploads' temporary directory ($made made) was not removed when pidlab serve stopped: $(ls "$tmp/server-tmp")"
  status=1
fi
exit $status
