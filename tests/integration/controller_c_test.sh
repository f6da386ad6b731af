#!/usr/bin/env bash
# The exported C in the lockstep: pidlab-controller-c (controller/export/
# process/: the module `pidlab export --scalar double` writes, lcm-gen -c's
# messages, liblcm's C API) takes pidlab-controller's place next to
# `pidlab launch --roles plant,disturbance`. Every episode must give the same
# trajectory (y, u, n at every step) and IAE, bit for bit, as the in-process
# sampled loop and as the C++ trio: default PID with a square disturbance (two
# episodes), every PID option branch (limits, back-calculation and clamping,
# derivative filter, on measurement, trapezoidal and forward Euler), and 5 %
# of the plant's messages dropped (resends the controller must re-answer).
# Run as: unshare -n bash controller_c_test.sh BIN_DIR
set -uo pipefail
bin=$(realpath -- "${1:?usage: controller_c_test.sh BIN_DIR}")
controller=$bin/pidlab-controller-c
pidlab=$bin/pidlab

# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
private_network_up
work=$(mktemp -d)
pc=
cleanup() { [[ -n $pc ]] && kill "$pc" 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT
cd "$work"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
url='udpm://239.255.76.67:7667?ttl=0'

start_controller() {  # the C controller, in the background
  "$controller" --lcm-url "$url" --verbose 2>>controller.err &
  pc=$!
}
stop_controller() {
  kill -TERM "$pc"; wait "$pc"; local rc=$?; pc=
  return $rc
}
same() {  # same NAME A.json A.csv B.json B.csv
  python3 - "$2" "$4" <<'PY' && cmp -s "$3" "$5"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
assert a['iae'] is not None, 'the loop is unstable: no IAE'
assert a['iae'] == b['iae'] and a['ise'] == b['ise'], (a['iae'], b['iae'])
PY
}
iae() { python3 -c 'import json,sys; print(repr(json.load(open(sys.argv[1]))["iae"]))' "$1"; }

"$controller" --lcm-url 'udpm://239.255.76.67:99999' 2>bad.err; rc=$?
check "a bad URL is exit 2 with one line" "[ $rc -eq 2 ] && [ \$(wc -l < bad.err) -eq 1 ]"
"$controller" --help >help.out 2>&1; rc=$?
check "--help is exit 0 and names every option" "[ $rc -eq 0 ] && grep -q -- --print-configs help.out && grep -q -- --lcm-url help.out"

run_case() {  # run_case NAME LAUNCH_FLAGS -- EVALUATE_FLAGS...
  local name=$1; shift
  local launch_flags=()
  while [[ $1 != -- ]]; do launch_flags+=("$1"); shift; done; shift
  local flags=(--loop sampled --horizon 2 "$@")
  "$pidlab" evaluate "${flags[@]}" --json --trajectory-csv "$name.local.csv" >"$name.local.json"
  : >controller.err
  start_controller
  "$pidlab" launch --roles plant,disturbance --lcm-url "$url" "${launch_flags[@]}" -- \
    pidlab evaluate --backend lcm "${flags[@]}" --json --trajectory-csv "$name.c.csv" >"$name.c.json" 2>"$name.launch.err"
  local rc=$?
  stop_controller
  check "$name: the trio with the C controller ran (exit $rc)" "[ $rc -eq 0 ]" ||
    { tail -3 "$name.launch.err"; cat controller.err; }
  check "$name: y, u, n at every step and IAE $(iae "$name.local.json") equal the in-process loop's bit for bit" \
    "same $name $name.c.json $name.c.csv $name.local.json $name.local.csv"
  check "$name: the controller stopped cleanly and counted no conflict or undecodable message" \
    "grep -q 'conflicts 0' controller.err"
}

# 1. The paper's oscillator, square disturbance (evaluate runs a disturbed and
#    an undisturbed episode), and the C++ trio on the same case.
run_case square -- --plant oscillator --gains 2,1,1.5 --disturbance square --disturbance-amplitude 0.2 \
  --disturbance-period 1
check "square: two episodes answered" "[ \$(grep -c ': done, 2000 commands' controller.err) -eq 2 ]"
"$pidlab" launch --lcm-url "$url" -- pidlab evaluate --backend lcm --loop sampled --horizon 2 --plant oscillator \
  --gains 2,1,1.5 --disturbance square --disturbance-amplitude 0.2 --disturbance-period 1 --json \
  --trajectory-csv square.cpp.csv >square.cpp.json 2>square.cpp.err
check "square: the C++ trio gives the same trajectory and IAE" \
  "same square square.c.json square.c.csv square.cpp.json square.cpp.csv"

# 2. Every branch of the discrete PID.
run_case limits_backcalc -- --plant double_integrator --gains 8,3,2 --output-limits -1,1.5 \
  --anti-windup back-calculation --derivative-filter 0.01 --derivative-on measurement --integral trapezoidal
run_case limits_clamping -- --plant oscillator --gains 2,1,1.5 --output-limits -0.5,0.8 \
  --anti-windup clamping --integral forward-euler --derivative-filter 0.002
check "limits: the loops did saturate" \
  "python3 -c \"import csv,sys; us=[float(r['u']) for r in csv.DictReader(open('limits_backcalc.c.csv'))]; vs=[float(r['u']) for r in csv.DictReader(open('limits_clamping.c.csv'))]; sys.exit(not (max(us)==1.5 and max(vs)==0.8))\""

# 2b. The third paper plant, the stepper motor of eq. (3), with limits, a
#     filter and back-calculation.
run_case stepper -- --plant stepper_motor --gains 2.6685,30,0.095 --output-limits -5,5 \
  --anti-windup back-calculation --derivative-filter 0.002 --integral trapezoidal

# 2c. 2-DOF setpoint weights on each paper plant, with limits, a filter and
#     anti-windup (the weights come from the episode's message).
run_case twodof_oscillator -- --plant oscillator --gains 2,1,1.5 --setpoint-weights 0.664,0.0136 \
  --output-limits -0.5,0.8 --anti-windup clamping --derivative-filter 0.01
run_case twodof_double_integrator -- --plant double_integrator --gains 8,3,2 --setpoint-weights 0.5,0.25 \
  --output-limits -1,1.5 --anti-windup back-calculation --derivative-filter 0.01 --integral trapezoidal
run_case twodof_stepper -- --plant stepper_motor --gains 2.6685,30,0.095 --setpoint-weights 0.8,0 \
  --output-limits -5,5 --anti-windup back-calculation --derivative-filter 0.002

# 2d. A reverse-acting plant (a negative gain) under the PID with gains all
#     <= 0 that `pidlab tune` gives it, saturating under clamping: the C
#     controller and the C++ trio carry the sign, and the loop is the mirror
#     of the direct-acting one (-G with -C: y and the IAE bit for bit, u negated).
run_case reverse -- --num -19 --den 2,1 --gains -0.9,-1.2,-0.03 --derivative-filter 0.0084 \
  --output-limits -0.1,0.1 --anti-windup clamping
"$pidlab" launch --lcm-url "$url" -- pidlab evaluate --backend lcm --loop sampled --horizon 2 --num -19 --den 2,1 \
  --gains -0.9,-1.2,-0.03 --derivative-filter 0.0084 --output-limits -0.1,0.1 --anti-windup clamping --json \
  --trajectory-csv reverse.cpp.csv >reverse.cpp.json 2>reverse.cpp.err
check "reverse: the C++ trio gives the same trajectory and IAE" \
  "same reverse reverse.c.json reverse.c.csv reverse.cpp.json reverse.cpp.csv"
"$pidlab" evaluate --loop sampled --horizon 2 --num 19 --den 2,1 --gains 0.9,1.2,0.03 --derivative-filter 0.0084 \
  --output-limits -0.1,0.1 --anti-windup clamping --json --trajectory-csv direct.csv >direct.json
check "reverse: the mirror of the direct-acting loop, y and IAE bit for bit, u negated, saturated" \
  "python3 -c \"import csv,json,sys; a=list(csv.DictReader(open('reverse.c.csv'))); b=list(csv.DictReader(open('direct.csv'))); ok=json.load(open('reverse.c.json'))['iae']==json.load(open('direct.json'))['iae'] and len(a)==len(b) and all(x['y']==y['y'] and float(x['u'])==-float(y['u']) for x,y in zip(a,b)) and max(abs(float(x['u'])) for x in a)==0.1; sys.exit(not ok)\""

# 2e. The setpoint filter (docs/two_dof.md), carried by the episode's message,
#     with weights, limits and clamping: the C controller and the C++ trio run
#     the in-process loop's filter, and it did move the response.
sf=(--loop sampled --horizon 2 --plant oscillator --gains 2,1,1.5 --setpoint-weights 0.6,0 --output-limits -0.5,0.8
  --anti-windup clamping --derivative-filter 0.01)
run_case setpoint_filter -- "${sf[@]:4}" --setpoint-filter 0.4
"$pidlab" launch --lcm-url "$url" -- pidlab evaluate --backend lcm "${sf[@]}" --setpoint-filter 0.4 --json \
  --trajectory-csv setpoint_filter.cpp.csv >setpoint_filter.cpp.json 2>setpoint_filter.cpp.err
check "setpoint_filter: the C++ trio gives the same trajectory and IAE" \
  "same setpoint_filter setpoint_filter.c.json setpoint_filter.c.csv setpoint_filter.cpp.json setpoint_filter.cpp.csv"
"$pidlab" evaluate "${sf[@]}" --json >unfiltered.json
check "setpoint_filter: the filter moved the setpoint response" \
  "[ \"\$(iae unfiltered.json)\" != \"\$(iae setpoint_filter.c.json)\" ]"

# 3. Loss: the plant and the disturbance throw 5 % of what they receive away,
#    so the plant resends y_k and the controller must repeat u_k.
run_case loss --drop-rate 0.05 -- --plant oscillator --gains 2,1,1.5
check "loss: the controller re-answered resent outputs" \
  "grep -o 'duplicates [0-9]*' controller.err | awk '{exit !(\$2 > 0)}'"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
