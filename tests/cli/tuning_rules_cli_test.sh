#!/usr/bin/env bash
# pidlab tune --method simc | amigo --rule pi | pid: the model and the rule's
# gains in the JSON, and the plants the rules refuse (exit 2, one line).
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab="$1"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

# 1 / ((s + 1)(0.2 s + 1)): the half rule gives the FOPDT K = 1, T = 1.1,
# L = 0.1; SIMC PI: Kc = 1.1 / 0.2 = 5.5, tau_I = min(1.1, 0.8) = 0.8.
"$pidlab" tune --num 1 --den 0.2,1.2,1 --method simc --rule pi --json > "$tmp/simc.json" 2>"$tmp/err"
check "tune --method simc --rule pi exits 0" "[ $? -eq 0 ]"
check "simc pi: the half rule's FOPDT and SIMC's gains" "python3 - \"$tmp/simc.json\" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
m = j['model']
assert m['kind'] == 'fopdt' and m['half_rule'] is True, m
assert abs(m['gain'] - 1) < 1e-12 and abs(m['time_constants'][0] - 1.1) < 1e-9 and abs(m['delay'] - 0.1) < 1e-9, m
g = j['gains']
assert abs(g['kp'] - 5.5) < 1e-9 and abs(g['ki'] - 5.5 / 0.8) < 1e-9 and g['kd'] == 0, g
r = j['tuning_rule']
assert r['rule'] == 'pi' and abs(r['kc'] - 5.5) < 1e-9 and abs(r['ti_s'] - 0.8) < 1e-9 and r['td_s'] == 0, r
assert r['controller_form'] == 'series' and r['evaluated_on'] == 'continuous' and r['delay_simulated'] is False, r
assert j['method'] == 'simc' and j['evaluations'] == 1 and j['refine']['verdict'] == 'not run', j['refine']
assert j['stable'] is True and j['iae'] > 0 and j['spec']['rule'] == 'pi' and j['spec']['method'] == 'simc'
PY"

# A plant with dead time on the continuous loop (docs/tuning.md "Dead time", the documented command):
# AMIGO PI for T = L = 1 gives K = 0.25, scored by the method of steps, delay_simulated true.
"$pidlab" tune --num 1 --den 1,1 --delay 1 --method amigo --rule pi --json > "$tmp/delay.json" 2>"$tmp/err"
check "tune --delay 1 --method amigo --rule pi on the continuous loop exits 0" "[ $? -eq 0 ]"
check "amigo pi on e^(-s)/(s+1): K = 0.25, evaluated on the continuous loop with its delay" "python3 - \"$tmp/delay.json\" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
r = j['tuning_rule']
assert abs(j['gains']['kp'] - 0.25) < 1e-9, j['gains']
assert r['evaluated_on'] == 'continuous' and r['delay_simulated'] is True, r
assert j['stable'] is True and j['iae'] > 0 and j['spec']['delay'] == 1, j
PY"

# (s + 1)^3: FOPDT T = 1 + 1/2 = 1.5, L = 1/2 + 1 = 1.5, so T = L as in
# Astrom and Hagglund's K = 1, T = L = 1 case: AMIGO PID K = 0.65,
# Ti = 1.2/1.1 L, Td = 0.5 L / 1.3.
"$pidlab" tune --num 1 --den 1,3,3,1 --method amigo --json > "$tmp/amigo.json"
check "tune --method amigo (rule pid by default) exits 0" "[ $? -eq 0 ]"
check "amigo pid: K = 0.65, Ti = 1.0909 L, Td = 0.3846 L" "python3 - \"$tmp/amigo.json\" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
m, r, g = j['model'], j['tuning_rule'], j['gains']
assert m['kind'] == 'fopdt' and abs(m['time_constants'][0] - 1.5) < 1e-4 and abs(m['delay'] - 1.5) < 1e-4, m
assert r['rule'] == 'pid' and r['controller_form'] == 'parallel', r
assert abs(r['kc'] - 0.65) < 1e-4 and abs(r['ti_s'] - 1.5 * 12 / 11) < 1e-4 and abs(r['td_s'] - 1.5 * 5 / 13) < 1e-4, r
assert abs(g['kp'] - 0.65) < 1e-4 and abs(g['ki'] - r['kc'] / r['ti_s']) < 1e-12 and abs(g['kd'] - r['kc'] * r['td_s']) < 1e-12, g
assert j['stable'] is True
PY"

# SIMC PID on (s + 1)^3: SOPDT T1 = 1.5, T2 = 1, theta = 0.5 (sorted T1 >= T2);
# Kc = 1.5, tau_I = 1.5, tau_D = 1: kp = 1.5 (1 + 1/1.5) = 2.5, ki = 1, kd = 1.5.
"$pidlab" tune --num 1 --den 1,3,3,1 --method simc --rule pid --json > "$tmp/simc_pid.json"
check "simc pid: series gains converted to parallel" "python3 - \"$tmp/simc_pid.json\" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
m, g = j['model'], j['gains']
assert m['kind'] == 'sopdt' and abs(m['delay'] - 0.5) < 1e-4, m
assert abs(g['kp'] - 2.5) < 1e-4 and abs(g['ki'] - 1) < 1e-4 and abs(g['kd'] - 1.5) < 1e-4, g
PY"

"$pidlab" tune --num 1 --den 0.2,1.2,1 --method amigo --rule pi > "$tmp/text" 2>&1
check "the text output names the rule and its model" "grep -q '^rule  *amigo pi on fopdt' $tmp/text"

bad() {
  local name="$1" needle="$2"; shift 2
  "$pidlab" tune "$@" >/dev/null 2>"$tmp/bad"; local rc=$?
  check "$name exits 2 with one line" "[ $rc -eq 2 ] && [ \$(wc -l < $tmp/bad) -eq 1 ]"
  check "$name: one line under 300 characters naming '$needle'" "only_line_ok $tmp/bad '$needle'"
}
bad "simc on the oscillator" "complex poles" --plant oscillator --method simc
bad "amigo on 1/s^2" "2 poles at s = 0" --plant linear --method amigo --rule pi
bad "simc on an unstable plant" "unstable pole" --num 1 --den 1,-1 --method simc
bad "amigo on a first-order plant without delay" "needs a dead time" --num 1 --den 1,1 --method amigo
bad "a rule that is not pi or pid" "must be pi or pid" --plant linear --method simc --rule pd
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
