#!/usr/bin/env bash
# Damaged and hostile logs against `pidlab replay`, inside the private network
# namespace ctest runs this in (unshare -n): a real log of four short
# episodes is recorded with `pidlab launch --log` (and once more with the
# step lanes), replayed cleanly, then log_mutator writes COUNT seeded mutants
# of them and runs BIN_DIR/pidlab replay on each (every second with --json). Every
# run must exit 0 or 1 with at most one line on stderr, without a crash, a
# hang or a sanitizer report, and stay under MAX_RSS_MB of peak RSS.
# usage: log_mutants_test.sh BIN_DIR COUNT [MAX_RSS_MB [TOOL_BIN_DIR]]
#   BIN_DIR       the pidlab under test (a sanitised build-asan/bin too)
#   TOOL_BIN_DIR  log_mutator and the trio that records the seed logs
#                 (default BIN_DIR)
set -u
BIN=$(realpath -- "${1:?usage: log_mutants_test.sh BIN_DIR COUNT [MAX_RSS_MB [TOOL_BIN_DIR]]}")
COUNT=${2:?usage: log_mutants_test.sh BIN_DIR COUNT [MAX_RSS_MB [TOOL_BIN_DIR]]}
MAX_RSS_MB=${3:-200}
TOOLS=$(realpath -- "${4:-$BIN}")
# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/../integration/lib.sh"
private_network_up
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
# A sanitizer report is a crash (abort), never a quiet exit 1.
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
unset PIDLAB_AUTH_KEY_FILE PIDLAB_LCM_URL PIDLAB_CHANNEL_PREFIX
fail() { echo "FAIL $*"; exit 1; }

# The seeds: three short evaluations (four episodes: the disturbed one also
# runs undisturbed) recorded by `pidlab launch --log` (the trio's base port:
# configurations, disturbance blocks, trajectory chunks, summaries), and the
# same traffic with the step lanes (PLANT_OUTPUT on port + 1, CONTROL on
# port + 2) recorded by two more lcm-loggers and merged in time order: every
# message kind replay reads.
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
loggers=()
for lane in 1 2; do
  lcm-logger -q -f --lcm-url="udpm://239.255.76.67:$((7667 + lane))?ttl=0&recv_buf_size=4194304" \
    "$TMP/lane$lane.lcm" >/dev/null 2>&1 & loggers+=($!)
done
for lane in 1 2; do
  wait_until 10 test -e "$TMP/lane$lane.lcm" || fail "lcm-logger of lane $lane did not start"
done
export TOOLS
"$TOOLS/pidlab" launch --lcm-url "$URL" --log "$TMP/seed.lcm" -- bash -c '
  "$TOOLS/pidlab" evaluate --backend lcm --plant double_integrator --gains 2,1,1.5 --loop sampled --horizon 1 \
    --json >/dev/null &&
  "$TOOLS/pidlab" evaluate --backend lcm --plant stepper --gains 1,0.5,0.01 --loop sampled --horizon 0.5 \
    --json >/dev/null &&
  "$TOOLS/pidlab" evaluate --backend lcm --plant oscillator --gains 2,1,1.5 --loop sampled --horizon 1 \
    --disturbance square --disturbance-amplitude 0.2 --json >/dev/null' 2> "$TMP/launch.err"
rc=$?
kill -INT "${loggers[@]}" 2>/dev/null; wait "${loggers[@]}" 2>/dev/null
[ $rc -eq 0 ] || fail "recording the seed log: $(grep -v '^pidlab-' "$TMP/launch.err" | head -3)"
python3 - "$TMP/full.lcm" "$TMP/seed.lcm" "$TMP/lane1.lcm" "$TMP/lane2.lcm" <<'PY' || fail "merging the seed logs"
import struct, sys
events = []
for path in sys.argv[2:]:
    b, i = open(path, "rb").read(), 0
    while i + 28 <= len(b):
        sync, num, ts, cl, dl = struct.unpack(">IqqII", b[i:i + 28])
        if sync != 0xEDA1DA01 or i + 28 + cl + dl > len(b): break
        events.append((ts, len(events), b[i + 28:i + 28 + cl], b[i + 28 + cl:i + 28 + cl + dl]))
        i += 28 + cl + dl
events.sort()
with open(sys.argv[1], "wb") as f:
    for n, (ts, _, channel, data) in enumerate(events):
        f.write(struct.pack(">IqqII", 0xEDA1DA01, n, ts, len(channel), len(data)) + channel + data)
PY
for seed in seed full; do
  "$BIN/pidlab" replay "$TMP/$seed.lcm" > "$TMP/$seed.txt" 2>&1 ||
    fail "$BIN/pidlab replay of the clean $seed.lcm: $(head -c 300 "$TMP/$seed.txt")"
  grep -q INCOMPLETE "$TMP/$seed.txt" && fail "the clean $seed.lcm is incomplete: $(grep INCOMPLETE "$TMP/$seed.txt")"
done
outputs=$(LC_ALL=C grep -ao PIDLAB_PLANT_OUTPUT "$TMP/full.lcm" | wc -l)
[ "$outputs" -gt 100 ] || fail "the step lanes were not recorded (only $outputs PLANT_OUTPUT events in full.lcm)"
echo "ok   seed logs: launch --log $(stat -c %s "$TMP/seed.lcm") bytes, with the step lanes $(stat -c %s "$TMP/full.lcm") bytes; $(grep -c complete "$TMP/seed.txt") episodes, replayed cleanly"

mkdir "$TMP/mutants"
jobs=$(( $(nproc) > 1 ? 2 : 1 ))  # two replays at a time (ctest gives this test two processors: PROCESSORS 2)
start=$(date +%s%N)
"$TOOLS/log_mutator" --pidlab "$BIN/pidlab" --seed-log "$TMP/seed.lcm" "$TMP/full.lcm" --count "$COUNT" \
  --seed 13 --work-dir "$TMP/mutants" --max-rss-mb "$MAX_RSS_MB" --timeout 20 --jobs "$jobs" \
  > "$TMP/mutator.out" 2> "$TMP/mutator.err"
rc=$?
tenths=$(( ($(date +%s%N) - start) / 100000000 ))
cat "$TMP/mutator.out"
grep -v "^log_mutator: [0-9]*/" "$TMP/mutator.err"
if [ $rc -ne 0 ]; then
  # Keep the failing mutants for a look (the temporary directory goes).
  keep=$(mktemp -d /tmp/log_mutants.XXXXXX); cp -r "$TMP/mutants" "$TMP/seed.lcm" "$TMP/full.lcm" "$keep/"
  echo "FAIL log mutants against $BIN/pidlab (exit $rc; mutants and seeds kept in $keep)"
  exit 1
fi
echo "PASS log mutants: $COUNT against $BIN/pidlab in $((tenths / 10)).$((tenths % 10)) s"
