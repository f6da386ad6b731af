#!/usr/bin/env bash
# An authenticated run logged and replayed (ctest runs this under unshare -n):
# launch --auth-key --log; replay with the key is complete and gives the live
# IAE bit for bit; without the key the tags are reported unverified; with
# another key every message is dropped as unauthenticated.
# usage: auth_log_test.sh BIN_DIR
set -u
BIN=$1
# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
private_network_up
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
fail=0
head -c 32 /dev/urandom > "$TMP/trio.key"; head -c 32 /dev/urandom > "$TMP/other.key"
"$BIN/pidlab" launch --auth-key "$TMP/trio.key" --log "$TMP/run.lcmlog" -- pidlab evaluate --backend lcm \
  --plant oscillator --gains 2,1,1.5 --loop sampled --horizon 3 --json > "$TMP/live.json" 2> "$TMP/launch.err" ||
  { echo "FAIL authenticated run: $(grep -v '^pidlab-' "$TMP/launch.err" | head -3)"; exit 1; }
live=$(grep -o '"iae":[^,]*' "$TMP/live.json" | head -1 | cut -d: -f2)
field() { python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
"$BIN/pidlab" replay "$TMP/run.lcmlog" --auth-key "$TMP/trio.key" --json > "$TMP/key.json" || fail=1
got=$(field "$TMP/key.json" "repr(j['episodes'][-1]['evaluation']['iae']) if j['episodes'] else 'none'")
complete=$(field "$TMP/key.json" "all(e['complete'] for e in j['episodes']) and len(j['episodes']) > 0")
if [ "$complete" = True ] && [ "$(field "$TMP/key.json" "j['unauthenticated_events']")" = 0 ]; then
  echo "ok   replay with the key: complete, last IAE $got (live $live)"
else echo "FAIL replay with the key: complete=$complete"; fail=1; fi
python3 -c "import sys; sys.exit(0 if float('$got') == float('$live') else 1)" ||
  { echo "FAIL replayed IAE $got differs from the live $live"; fail=1; }
"$BIN/pidlab" replay "$TMP/run.lcmlog" --json > "$TMP/nokey.json" || fail=1
[ "$(field "$TMP/nokey.json" "j['unverified_events'] > 0")" = True ] && echo "ok   replay without a key reports unverified tags" ||
  { echo "FAIL replay without a key did not report unverified tags"; fail=1; }
"$BIN/pidlab" replay "$TMP/run.lcmlog" --auth-key "$TMP/other.key" --json > "$TMP/other.json" || fail=1
if [ "$(field "$TMP/other.json" "j['unauthenticated_events'] > 0 and j['pidlab_messages'] == 0")" = True ]; then
  echo "ok   replay with another key drops every message as unauthenticated"
else echo "FAIL replay with another key used messages"; fail=1; fi
[ $fail -eq 0 ] && echo "PASS auth log" || echo "FAIL auth log"
exit $fail
