#!/usr/bin/env bash
# The 2-DOF PID on the command line (docs/two_dof.md): --setpoint-weights is
# validated (exit 2, one line naming the value), b = c = 1 is the 1-DOF
# result bit for bit, --derivative-on measurement is c = 0, MATLAB's PIDF2
# example as docs/two_dof.md runs it, and tune --two-dof on a paper plant:
# load IAE and Ms unchanged, the setpoint overshoot lower.
set -uo pipefail
pidlab="$1"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
matlab=(--num 1 --den 1,0.5,0.1 --gains 1.12,0.23,1.3 --derivative-filter 0.122)

# Bad weights: exit 2, one line naming the value.
for w in 1.5,0 -0.1,1 0.5,nan 1,inf 0.5; do
  "$pidlab" evaluate "${matlab[@]}" --setpoint-weights "$w" >"$tmp/out" 2>"$tmp/err"
  rc=$?
  check "--setpoint-weights $w: exit 2 with one line" \
    "[ $rc -eq 2 ] && [ \$(wc -l <$tmp/err) -eq 1 ] && grep -q -- '--setpoint-weights' $tmp/err"
done
"$pidlab" evaluate "${matlab[@]}" --derivative-on measurement --setpoint-weights 1,0.5 >"$tmp/out" 2>"$tmp/err"
rc=$?
check "--derivative-on measurement with c = 0.5: exit 2, one line ($(cat "$tmp/err"))" \
  "[ $rc -eq 2 ] && [ \$(wc -l <$tmp/err) -eq 1 ] && grep -q 'derivative-on' $tmp/err"

# b = c = 1 is the 1-DOF loop; measurement is c = 0; on both loops.
same() {  # same NAME ARGS_A -- ARGS_B: identical JSON but for the spec
  local name=$1; shift
  local a=() b=()
  while [ "$1" != "--" ]; do a+=("$1"); shift; done; shift; b=("$@")
  "$pidlab" evaluate --json "${a[@]}" | jq -S 'del(.spec)' >"$tmp/a.json"
  "$pidlab" evaluate --json "${b[@]}" | jq -S 'del(.spec)' >"$tmp/b.json"
  check "$name" "cmp -s $tmp/a.json $tmp/b.json && jq -e '.stable' $tmp/a.json >/dev/null"
}
for loop in continuous sampled; do
  same "$loop: --setpoint-weights 1,1 is the 1-DOF result bit for bit" \
    "${matlab[@]}" --loop $loop -- "${matlab[@]}" --loop $loop --setpoint-weights 1,1
  same "$loop: --derivative-on measurement is --setpoint-weights 1,0 bit for bit" \
    "${matlab[@]}" --loop $loop --derivative-on measurement -- "${matlab[@]}" --loop $loop --setpoint-weights 1,0
  "$pidlab" evaluate --json "${matlab[@]}" --loop $loop >"$tmp/w11.json"
  "$pidlab" evaluate --json "${matlab[@]}" --loop $loop --setpoint-weights 0.2,0 >"$tmp/w20.json"
  check "$loop: the load IAE and Ms do not depend on the weights, the setpoint IAE does" \
    "[ \"\$(jq '[.load_iae, .robustness.ms]' $tmp/w11.json)\" = \"\$(jq '[.load_iae, .robustness.ms]' $tmp/w20.json)\" ] &&
     [ \"\$(jq .iae $tmp/w11.json)\" != \"\$(jq .iae $tmp/w20.json)\" ]"
done

# MATLAB's PIDF2 example, as docs/two_dof.md runs it.
"$pidlab" evaluate --num 1 --den 1,0.5,0.1 --gains 1.12,0.23,1.3 --derivative-filter 0.122 \
  --setpoint-weights 0.664,0.0136 --sample-time 0.5 --json >"$tmp/pidf2.json"
"$pidlab" evaluate --num 1 --den 1,0.5,0.1 --gains 1.12,0.23,1.3 --derivative-filter 0.122 \
  --sample-time 0.5 --json >"$tmp/pidf.json"
check "MATLAB's PIDF2 example: less overshoot than the 1-DOF PIDF, the same load IAE and Ms" \
  "/usr/bin/python3 - $tmp/pidf2.json $tmp/pidf.json <<'PY'
import json, sys
two, one = (json.load(open(f)) for f in sys.argv[1:3])
print('info PIDF2: iae %.6f overshoot %.3f %% settling %.3f s; PIDF: iae %.6f overshoot %.3f %% settling %.3f s; load iae %.6f; Ms %.4f'
      % (two['iae'], two['overshoot_pct'], two['settling_time_s'], one['iae'], one['overshoot_pct'],
         one['settling_time_s'], two['load_iae'], two['robustness']['ms']))
assert two['spec']['setpoint_weights'] == [0.664, 0.0136], two['spec']
assert two['overshoot_pct'] < one['overshoot_pct'], (two['overshoot_pct'], one['overshoot_pct'])
assert two['load_iae'] == one['load_iae'] and two['robustness']['ms'] == one['robustness']['ms']
PY"

# tune --two-dof on the three paper plants: the oscillator and the double
# integrator tuned hard for load rejection (the oscillator's as
# docs/two_dof.md runs it), the stepper motor with the robust preset.
two_dof() {  # two_dof PLANT ARGS...
  local plant=$1; shift
  "$pidlab" tune --plant "$plant" "$@" --two-dof --json >"$tmp/$plant.json" 2>"$tmp/$plant.err"
  local rc=$?
  check "tune --two-dof on $plant exits 0 ($(head -1 "$tmp/$plant.err"))" "[ $rc -eq 0 ]"
  check "tune --two-dof on $plant: load IAE and Ms unchanged, setpoint overshoot lower" \
    "/usr/bin/python3 - $tmp/$plant.json $plant <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
t = j['two_dof']
assert t['ran'], t
b, a = t['before'], t['after']
print('info %s: b = %.6g, c = %.6g; setpoint IAE %.6g -> %.6g, overshoot %.4g %% -> %.4g %%; load IAE %.6g -> %.6g; Ms %.6g -> %.6g'
      % (sys.argv[2], a['setpoint_weights'][0], a['setpoint_weights'][1], b['setpoint']['iae'], a['setpoint']['iae'],
         b['setpoint']['overshoot_pct'], a['setpoint']['overshoot_pct'], b['load']['iae'], a['load']['iae'],
         b['ms'], a['ms']))
assert b['setpoint_weights'] == [1, 1], b
assert a['load']['iae'] == b['load']['iae'] and a['ms'] == b['ms'], (a, b)
assert a['setpoint']['overshoot_pct'] < b['setpoint']['overshoot_pct'], (a, b)
assert a['setpoint']['iae'] <= b['setpoint']['iae'], (a, b)
assert j['spec']['two_dof'] is True and j['load_iae'] == a['load']['iae'], j['load_iae']
assert j['overshoot_pct'] == a['setpoint']['overshoot_pct'], (j['overshoot_pct'], a)
assert j['robustness']['ms'] == a['ms'], (j['robustness']['ms'], a)
PY"
}
two_dof oscillator --objective load-iae --derivative-filter-ratio 10 --max-ms 1.6 --method nelder-mead --max-evals 400
two_dof double_integrator --objective load-iae --derivative-filter-ratio 10 --max-ms 1.6 --method nelder-mead \
  --max-evals 400
two_dof stepper_motor --robust
"$pidlab" tune --plant oscillator --objective load-iae --derivative-filter-ratio 10 --max-ms 1.6 \
  --method nelder-mead --max-evals 400 --two-dof >"$tmp/tune.txt" 2>&1
check "tune --two-dof prints the weights and both responses" \
  "grep -q '^two-dof  *setpoint weights b = ' $tmp/tune.txt && [ \$(grep -c 'setpoint IAE' $tmp/tune.txt) -eq 2 ]"

# The commands docs/two_dof.md shows are the ones run above.
doc="$(dirname "${BASH_SOURCE[0]}")/../../docs/two_dof.md"
check "docs/two_dof.md shows the commands this test runs" \
  "grep -qxF 'pidlab evaluate --num 1 --den 1,0.5,0.1 --gains 1.12,0.23,1.3 --derivative-filter 0.122 --setpoint-weights 0.664,0.0136 --sample-time 0.5' $doc &&
   grep -qxF 'pidlab tune --plant oscillator --objective load-iae --derivative-filter-ratio 10 --max-ms 1.6 --method nelder-mead --max-evals 400 --two-dof' $doc"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
