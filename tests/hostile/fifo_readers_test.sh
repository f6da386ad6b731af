#!/usr/bin/env bash
# Every reader of a file the user names, given a FIFO with no writer
# (docs/security.md, "Readers never wait"): each command must exit 2 within
# 1 s with one line on stderr that names the FIFO, instead of waiting for a
# writer for ever. The readers: --spec (evaluate, tune, export), export
# --from, --model and --plant model:F, identify --csv and --log, replay,
# plot --log, report --paper-tables, --auth-key and launch --controller
# pil:DIR (its pil.json). In a private network namespace of its own, so
# that a launch that did start a trio would talk to no one.
#   fifo_readers_test.sh PIDLAB_BINARY
set -u
pidlab=$(realpath -- "${1:?usage: fifo_readers_test.sh PIDLAB_BINARY}")
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo ||
  { echo "FAIL cannot set up the private namespace's loopback"; exit 1; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fifo=$tmp/fifo
mkfifo "$fifo" || { echo "FAIL cannot make a FIFO in $tmp"; exit 1; }
mkdir "$tmp/pil" && mkfifo "$tmp/pil/pil.json"
failures=0 runs=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }

# refused WHAT NEEDLE ARGS...: exit 2 within 1 s (timeout gives 124 after
# 5 s), exactly one line on stderr, naming NEEDLE.
refused() {
  local what=$1 needle=$2; shift 2
  local start end rc=0
  start=$(date +%s%N)
  (cd "$tmp" && timeout 5 "$pidlab" "$@" >"$tmp/out" 2>"$tmp/err" </dev/null) || rc=$?
  end=$(date +%s%N)
  runs=$((runs + 1))
  local ms=$(((end - start) / 1000000)) lines
  lines=$(wc -l <"$tmp/err")
  if [ "$rc" -ne 2 ] || [ "$ms" -gt 1000 ] || [ "$lines" -ne 1 ] || ! grep -qF -- "$needle" "$tmp/err"; then
    fail "$what: exit $rc in $ms ms, $lines lines: $(head -c 300 "$tmp/err")"
  else
    echo "ok   $what: exit 2 in $ms ms: $(cat "$tmp/err")"
  fi
}

refused "evaluate --spec FIFO" "$fifo" evaluate --spec "$fifo"
refused "tune --spec FIFO" "$fifo" tune --spec "$fifo"
refused "export --spec FIFO" "$fifo" export --spec "$fifo" --lang c --out "$tmp/export"
refused "export --from FIFO" "$fifo" export --from "$fifo" --lang c --out "$tmp/export"
refused "evaluate --model FIFO" "$fifo" evaluate --model "$fifo" --gains 1,0.1,0
refused "evaluate --plant model:FIFO" "$fifo" evaluate --plant "model:$fifo" --gains 1,0.1,0
refused "identify --csv FIFO" "$fifo" identify --csv "$fifo" --model p1d
refused "identify --log FIFO" "$fifo" identify --log "$fifo" --model p1d
refused "replay FIFO" "$fifo" replay "$fifo"
refused "plot --log FIFO" "$fifo" plot --log "$fifo" --out "$tmp/plot"
refused "report --paper-tables FIFO" "$fifo" report --quick --no-figures --paper-tables "$fifo" --out "$tmp/report"
refused "replay --auth-key FIFO" "$fifo" replay --redrive --auth-key "$fifo" "$fifo"
refused "launch --auth-key FIFO" "$fifo" launch --auth-key "$fifo" -- true
refused "launch --controller pil:DIR with a FIFO for pil.json" "pil.json" launch --controller "pil:$tmp/pil" -- true
[ -d "$tmp/export" ] && fail "export made its --out folder before refusing the FIFO"
echo "fifo_readers_test: $runs readers, $failures failures"
[ "$failures" -eq 0 ]
