#!/usr/bin/env bash
# Hostile traffic against a live trio, inside the private network namespace
# ctest runs this in (unshare -n): for every attack class of hostile_stranger,
# episodes run while the stranger attacks. Without a key every episode must
# end bit-identical to the in-process loop or fail loudly (exit 1, one line);
# huge arrays and absurd steps must change nothing. With --auth-key every
# episode must be bit-identical. No process may crash or report a sanitizer
# error.
# usage: hostile_test.sh BIN_DIR MODE MESSAGES   (MODE: nokey | key)
set -u
BIN=$1 MODE=$2 MESSAGES=${3:-20000}
# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/../integration/lib.sh"
private_network_up
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
PIDLAB="$BIN/pidlab"
EVAL=(--plant double_integrator --gains 2,1,1.5 --loop sampled --horizon 2 --disturbance square --disturbance-amplitude 0.2)
"$PIDLAB" evaluate "${EVAL[@]}" --json | sed 's/"backend":"[a-z]*",//; s/,"steps_per_second":[^,}]*//' > "$TMP/ref.json" || exit 1
KEYARGS=()
if [ "$MODE" = key ]; then head -c 32 /dev/urandom > "$TMP/trio.key"; KEYARGS=(--auth-key "$TMP/trio.key"); fi
CLASSES="fuzz huge-arrays absurd-steps forge-control forge-disturbance forge-output forge-chunk forge-summary replay"
PER=$(( MESSAGES / 9 ))
export BIN PIDLAB TMP URL MODE PER CLASSES
export EVAL_ARGS="${EVAL[*]}"
"$PIDLAB" launch --lcm-url "$URL" "${KEYARGS[@]}" -- bash -c '
  fail=0 total_sent=0 identical=0 loud=0
  for cls in $CLASSES; do
    "$BIN/hostile_stranger" --lcm-url "$URL" --attack $cls --messages $PER --seconds 8 --seed 7 > "$TMP/s.out" 2>&1 & s=$!
    runs=0
    while kill -0 $s 2>/dev/null && [ $runs -lt 6 ] || [ $runs -eq 0 ]; do
      runs=$((runs + 1))
      "$PIDLAB" evaluate --backend lcm $EVAL_ARGS --json > "$TMP/out.json" 2> "$TMP/err"; rc=$?
      if grep -q "AddressSanitizer\|runtime error" "$TMP/err"; then echo "FAIL $cls: sanitizer report: $(head -3 "$TMP/err")"; fail=1; fi
      if [ $rc -eq 0 ]; then
        sed "s/\"backend\":\"[a-z]*\",//; s/,\"steps_per_second\":[^,}]*//" "$TMP/out.json" > "$TMP/got.json"
        if cmp -s "$TMP/got.json" "$TMP/ref.json"; then identical=$((identical + 1))
        else echo "FAIL $cls: exit 0 with a result that is not bit-identical"; fail=1; fi
      else
        lines=$(grep -v "^pidlab-" "$TMP/err" | wc -l)
        if [ "$MODE" = key ]; then echo "FAIL $cls: with a key the episode failed: $(head -c 300 "$TMP/err")"; fail=1
        elif [ $rc -ne 1 ] || [ "$lines" -ne 1 ]; then echo "FAIL $cls: exit $rc, $lines lines: $(head -c 300 "$TMP/err")"; fail=1
        elif [ "$cls" = huge-arrays ] || [ "$cls" = absurd-steps ]; then echo "FAIL $cls changed an episode: $(head -c 300 "$TMP/err")"; fail=1
        elif LC_ALL=C grep -q "$(printf "\x1b")" "$TMP/err"; then echo "FAIL $cls: wire text printed unescaped"; fail=1
        else loud=$((loud + 1)); fi
      fi
    done
    wait $s || { echo "FAIL $cls: the stranger failed: $(cat "$TMP/s.out")"; fail=1; }
    sent=$(grep -o "[0-9]* messages sent" "$TMP/s.out" | cut -d" " -f1)
    total_sent=$((total_sent + ${sent:-0}))
    for role in PLANT CONTROLLER DISTURBANCE; do
      pid_var=PIDLAB_${role}_PID
      kill -0 "${!pid_var}" 2>/dev/null || { echo "FAIL $cls: pidlab-${role,,} died"; fail=1; }
    done
    echo "ok   $cls: $runs episodes under ${sent:-0} hostile messages"
  done
  echo "hostile ($MODE): $total_sent messages, $identical episodes bit-identical, $loud failed loudly"
  [ $total_sent -ge $(( PER * 9 * 9 / 10 )) ] || { echo "FAIL only $total_sent messages were sent"; fail=1; }
  exit $fail' 2> "$TMP/launch.err"
rc=$?
if grep -q "killed by signal\|AddressSanitizer\|runtime error" "$TMP/launch.err"; then
  echo "FAIL a process crashed: $(grep "killed by signal\|AddressSanitizer\|runtime error" "$TMP/launch.err" | head -3)"; rc=1
fi
[ $rc -eq 0 ] && echo "PASS hostile $MODE" || echo "FAIL hostile $MODE (exit $rc)"
exit $rc
