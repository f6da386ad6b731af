#!/usr/bin/env bash
# pidlab tune --robust on the continuous loop of a plant with dead time
# (docs/deadtime.md, "The slowest time constant with dead time"): it finds
# gains within the preset's bounds in seconds, and the analysis reports a
# finite slowest time constant within the bound.
set -uo pipefail
pidlab="$1"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

start=$(date +%s)
"$pidlab" tune --robust --plant custom --num 1 --den 1,1 --delay 0.5 --bounds 0,3 --max-evals 80 \
  --horizon 25 --sample-time 0.05 --json \
  > "$tmp/out.json" 2>"$tmp/err"
rc=$?
took=$(( $(date +%s) - start ))
check "tune --robust on 1/(s + 1) e^(-0.5 s) exits 0" "[ $rc -eq 0 ]"
echo "info tune --robust took ${took} s (a figure, not a check: speed is measured in bench/)"
check "its gains meet every bound with a finite slowest time constant" "/usr/bin/python3 - \"$tmp/out.json\" <<'PY'
import json, math, sys
j = json.load(open(sys.argv[1]))
assert j['stable'] is True, j.get('message')
r = j['robustness']
tau, bound = r['slowest_time_constant_s'], j['spec']['max_time_constant']
assert tau is not None and math.isfinite(tau) and 0 < tau <= bound, (tau, bound)
assert 'slowest_time_constant_s' not in r.get('notes', {}), r['notes']
assert r['violations'] == [], r['violations']
assert r['ms'] <= 1.6 * (1 + 1e-6), r['ms']
PY"

"$pidlab" evaluate --plant custom --num 1 --den 1,1 --delay 0.5 --derivative-filter-ratio 10 \
  --gains "$(/usr/bin/python3 -c "import json,sys; g=json.load(open(sys.argv[1]))['gains']; print('%r,%r,%r' % (g['kp'], g['ki'], g['kd']))" "$tmp/out.json")" \
  --max-time-constant 2.5 --max-ms 1.6 > "$tmp/out.txt" 2>&1
check "evaluate of the tuned gains prints a slowest tau in seconds and no violation" \
  "grep -Eq 'slowest tau +[0-9.e+-]+ s' $tmp/out.txt && ! grep -q VIOLATES $tmp/out.txt"
"$pidlab" tune --robust --plant double_integrator --max-evals 200 > "$tmp/verdict.txt" 2>&1
check "the verdict line does not say 'not run' twice" \
  "grep -q '^verdict *not run: setpoint-load' $tmp/verdict.txt && ! grep -q 'not run: not run' $tmp/verdict.txt"

"$pidlab" evaluate --plant custom --num 1 --den 1,1 --delay 1 --gains 1,0,0 --json > "$tmp/ev.json"
check "evaluate reports the slowest time constant of e^(-s)/(s + 1) under kp = 1" "/usr/bin/python3 - \"$tmp/ev.json\" <<'PY'
import json, sys
import numpy as np
from scipy.optimize import fsolve
j = json.load(open(sys.argv[1]))
tau = j['robustness']['slowest_time_constant_s']
# The rightmost root of s + 1 + e^(-s) = 0 (a complex pair), by scipy.
f = lambda v: [np.real(complex(*v) + 1 + np.exp(-complex(*v))), np.imag(complex(*v) + 1 + np.exp(-complex(*v)))]
re, im = fsolve(f, [-0.5, 1.5], xtol=1e-14)
assert abs(tau - (-1 / re)) < 1e-7 * tau, (tau, re, im)
PY"

echo "robust_delay: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
