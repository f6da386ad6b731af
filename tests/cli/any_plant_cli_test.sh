#!/usr/bin/env bash
# Any plant, one command (docs/tuning.md, "Any plant"): the section's commands
# as written, and on the newcomer's plants the default tune is the design
# engine (method optimal), with its own filter, a stable loop settled within a
# time scale taken from the plant, Ms within its bound (SIMC's, within
# [1.4, 1.6]), overshoot at most 10 %, a load integral below SIMC's at an Ms
# no higher; migo's knobs move its design; the paper's plants keep eq. (4) and
# a budget asks for the multi-start; bad knob values exit 2 with one line.
#   any_plant_cli_test.sh PIDLAB_BINARY TUNING_MD
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab=$(realpath -- "$1")
doc=$(realpath -- "$2")
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

# ---- docs/tuning.md's "Any plant" commands as written (pidlab on PATH).
mkdir bin && ln -s "$pidlab" bin/pidlab
awk '/^## Any plant/{on=1} /^## Tuning rules/{on=0} on' "$doc" |
  awk '/^```sh$/{on=1; next} /^```$/{on=0} on' >commands.sh
check "the section has its eight commands" "[ \$(grep -c '^pidlab tune' commands.sh) -eq 8 ]"
i=0
while IFS= read -r line; do
  i=$((i + 1))
  check "docs: $line" "PATH=\"$tmp/bin:\$PATH\" bash -c '$line' > doc$i.out 2> doc$i.err"
done < <(grep '^pidlab ' commands.sh)

# ---- The newcomer's plants with only their flags.
verify() {  # name, json, simc json or ''
  /usr/bin/python3 - "$2" "$3" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j['method'] == 'optimal', j['method']
assert j['stable'] is True, 'unstable'
g = j['gains']
assert g['kd'] > 0 and g['tf'] > 0, g
ms = j['robustness']['ms']
bound = j['design']['ms_bound']
assert 1.4 <= bound <= 1.6 and 0.99 * bound <= ms <= bound * (1 + 1e-3), (ms, bound)
# At most 10 %, by the weights, or (a lag-dominant plant, whose integral
# action overshoots by itself) by a setpoint filter with them.
d = j['design']
assert j['overshoot_pct'] <= 10 + 1e-6 and d['overshoot_met'], (j['overshoot_pct'], d['setpoint_note'])
t = j['time_scale']
assert t['source'] == 'plant' and t['horizon_s'] == j['spec']['horizon'] and t['sample_time_s'] == j['spec']['sample_time'], t
assert j['settling_time_s'] < t['horizon_s'] / 2, (j['settling_time_s'], t)
b, c = j['two_dof']['setpoint_weights']
assert 0 <= c <= 1 and 0 <= b <= 1 and j['two_dof']['setpoint_filter_s'] >= 0, j['two_dof']
assert j['two_dof']['setpoint_filter_s'] == d['setpoint_filter_s'], j['two_dof']
if sys.argv[2]:
    s = json.load(open(sys.argv[2]))
    s_ms = s['robustness']['ms']
    load, s_load = j['load_iae'] * t['sample_time_s'], s['load_iae'] * s['spec']['sample_time']
    assert ms <= s_ms + 1e-3 and load < s_load, (ms, s_ms, load, s_load)
PY
}
for case in "fopdt|--num 1 --den 10,1 --delay 2" "thermal|--num 2 --den 60,1 --delay 8"; do
  name=${case%%|*}; flags=${case#*|}
  # shellcheck disable=SC2086
  "$pidlab" tune $flags --json > $name.json 2>$name.err
  check "$name: tune $flags exits 0" "[ $? -eq 0 ]"
  n=$(/usr/bin/python3 -c "import json;s=json.load(open('$name.json'))['spec'];print(s['horizon'],s['sample_time'])")
  # shellcheck disable=SC2086
  "$pidlab" tune $flags --method simc --rule pi --horizon ${n% *} --sample-time ${n#* } --json > $name.simc.json
  check "$name: the engine, filtered, stable, Ms at SIMC's bound, overshoot <= 10 % or said, settled, load below SIMC's" \
    "verify $name $name.json $name.simc.json"
  # shellcheck disable=SC2086
  "$pidlab" tune --spec $name.json --json > $name.again.json
  check "$name: the echoed spec runs again to the same gains and time scale" "/usr/bin/python3 - <<'PY'
import json
a, b = json.load(open('$name.json')), json.load(open('$name.again.json'))
assert a['gains'] == b['gains'] and a['time_scale'] == b['time_scale'], (a['gains'], b['gains'], b['time_scale'])
PY"
done

# ---- export --from takes the design's setpoint weights with its gains, at a dt
# where the loop is stable.
"$pidlab" export --from fopdt.json --dt 0.01 --lang c --out fw > export.out 2> export.err
check "export --from the design: its gains and b, c in the C, the loop checked stable at dt" "/usr/bin/python3 - <<'PY'
import json, re
j = json.load(open('fopdt.json'))
c = open('fw/pidlab_pid.c').read()
h = open('fw/pidlab_pid.h').read()
b, cw = j['two_dof']['setpoint_weights']
assert 'Loop at dt: the sampled loop of plant custom is stable' in h, h[:2000]
m = re.search(r'Tuned: kp ([^,]+), ki ([^,]+), kd ([^,]+), tf ([^ ]+) s, b ([^,]+), c ([^,]+),', h)
assert m and abs(float(m.group(5)) - b) < 1e-5 * max(1, b) and abs(float(m.group(6)) - cw) < 1e-5, m and m.groups()
assert abs(float(m.group(1)) - j['gains']['kp']) < 1e-5 * j['gains']['kp'], m.groups()
PY"

# ---- migo's knobs: a tighter bound is slower and more robust; a response time
# slows the crossover to 2/T (the engine's: tests/cli/design_cli_test.sh).
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method migo --json > migo.json
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method migo --robustness 1.3 --json > tight.json
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method migo --response-time 20 --json > slow.json
check "--robustness 1.3: Ms <= 1.3, and a smaller ki than the default" "/usr/bin/python3 - <<'PY'
import json
d, t = json.load(open('migo.json')), json.load(open('tight.json'))
assert t['robustness']['ms'] <= 1.3 * (1 + 1e-3) and t['gains']['ki'] < d['gains']['ki'], (t['robustness']['ms'], t['gains'])
assert t['migo']['robustness_reason'] == 'given', t['migo']
PY"
check "--response-time 20: the crossover at most 0.1 rad/s" "/usr/bin/python3 - <<'PY'
import json
s = json.load(open('slow.json'))
assert s['migo']['crossover_rad_s'] <= 0.1 + 1e-12 and s['stable'], s['migo']
PY"

# ---- SIMC and AMIGO's PID on a first-order plant with dead time: a filter, not a refusal.
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method amigo --rule pid --json > amigo.json 2>amigo.err
check "amigo --rule pid on 1/(10s+1) e^-2s returns its gains with tf = Td/10" "/usr/bin/python3 - <<'PY'
import json
j = json.load(open('amigo.json'))
g = j['gains']
assert j['stable'] and g['kd'] > 0 and abs(g['tf'] - g['kd'] / (10 * g['kp'])) < 1e-12, g
PY"

# ---- SIMC's knob: --tau-c 4 on K = 1, T = 10, L = 2 gives Kc = T / (K (tau_c + L)) = 10/6.
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method simc --rule pi --tau-c 4 --json > tauc.json
check "simc --tau-c 4: Kc = 10/6, Ti = min(T, 4 (tau_c + L)) = 10" "/usr/bin/python3 - <<'PY'
import json
j = json.load(open('tauc.json'))
g = j['gains']
assert abs(g['kp'] - 10 / 6) < 1e-12 and abs(g['ki'] - 10 / 6 / 10) < 1e-12, g
assert j['spec']['tau_c'] == 4 and 'tau_c = 4 s (given)' in j['tuning_rule']['message'], j['tuning_rule']
PY"

# ---- The paper's plants keep eq. (4); a budget asks for the multi-start.
"$pidlab" tune --plant oscillator --max-evals 300 --design-points 64 --json > paper.json
check "the paper's oscillator with a budget: multi-start on eq. (4)'s 25 s at 0.05 s" "/usr/bin/python3 - <<'PY'
import json
j = json.load(open('paper.json'))
assert j['method'] == 'multi-start' and j['spec']['horizon'] == 25 and j['spec']['sample_time'] == 0.05, j['spec']
assert j['time_scale']['source'] == 'eq. (4)', j['time_scale']
PY"
# The newcomer's `tune --plant stepper`: the engine on eq. (4), off the box's
# edge, and its load IAE far below the multi-start's on the paper's objective.
"$pidlab" tune --plant stepper --json > stepper.json
"$pidlab" tune --plant stepper --method multi-start --json > stepper_ms.json
check "tune --plant stepper: the engine, not on the box's edge, Ms <= 1.4, overshoot <= 10 %" "/usr/bin/python3 - <<'PY'
import json
j = json.load(open('stepper.json'))
m = json.load(open('stepper_ms.json'))
assert j['method'] == 'optimal' and j['time_scale']['source'] == 'eq. (4)', (j['method'], j['time_scale'])
assert j['design']['robustness_reason'].startswith('the default'), j['design']
assert not j.get('at_bounds'), j.get('at_bounds')
assert m['at_bounds'], m.get('at_bounds')  # the paper's objective ends on ki = 30
assert j['robustness']['ms'] <= 1.4 + 1e-3, j['robustness']
assert j['overshoot_pct'] <= 10 + 1e-6, j['overshoot_pct']
assert j['load_iae'] < m['load_iae'] / 10, (j['load_iae'], m['load_iae'])
PY"

# ---- One knob, two words: a phase margin; a crossover is a response time.
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method migo --robustness 60 --json > pm60.json
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method migo --robustness 45 --json > pm45.json
check "--robustness 60: a phase margin of at least 60 deg, less robust at 45" "/usr/bin/python3 - <<'PY'
import json
a, b = json.load(open('pm60.json')), json.load(open('pm45.json'))
assert a['migo']['phase_margin_deg'] == 60 and a['robustness']['phase_margin_deg'] >= 60 - 0.5, a['robustness']['phase_margin_deg']
assert 1.05 <= a['migo']['ms_bound'] < b['migo']['ms_bound'] <= 4, (a['migo'], b['migo'])
assert b['robustness']['phase_margin_deg'] >= 45 - 0.5 and a['gains']['ki'] < b['gains']['ki'], (a['gains'], b['gains'])
PY"
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method migo --crossover 0.1 --json > w.json
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method migo --response-time 20 --json > t.json
check "--crossover 0.1 is --response-time 20" "/usr/bin/python3 - <<'PY'
import json
w, t = json.load(open('w.json')), json.load(open('t.json'))
assert w['gains'] == t['gains'] and w['migo']['response_time_s'] == 20, (w['gains'], t['gains'], w['migo'])
assert w['migo']['crossover_rad_s'] <= 0.1 * (1 + 1e-6), w['migo']
PY"

# ---- evaluate and plot take the loop's time scale.
"$pidlab" evaluate --num 2 --den 60,1 --delay 8 --gains 3,0.05,10 --derivative-filter-ratio 10 --json > ev.json
check "evaluate on the thermal plant: the closed loop's time scale, said so" "/usr/bin/python3 - <<'PY'
import json
j = json.load(open('ev.json'))
t = j['time_scale']
assert t['source'] == 'plant' and t['reason'].startswith('the closed loop of the gains'), t
assert t['horizon_s'] == j['spec']['horizon'] and t['horizon_s'] >= 10 * j['robustness']['slowest_time_constant_s'], (t, j['robustness']['slowest_time_constant_s'])
PY"
"$pidlab" evaluate --spec ev.json --json > ev2.json
check "its spec echo runs again to the same numbers and time scale" "/usr/bin/python3 - <<'PY'
import json
a, b = json.load(open('ev.json')), json.load(open('ev2.json'))
assert a['iae'] == b['iae'] and a['time_scale'] == b['time_scale'], (a['time_scale'], b['time_scale'])
PY"
"$pidlab" evaluate --plant stepper --gains 20.8836,26.607,12.4866 > paper_ev.txt
check "evaluate on the paper's stepper keeps eq. (4) and its IAE" \
  "grep -q '^time scale .*(eq. (4))' paper_ev.txt && grep -q '^IAE (eq. 4)  *1.97506' paper_ev.txt"
"$pidlab" plot --plant stepper --gains 2.18522,97.6195,0.135618 --derivative-filter 0.00620615 --out fig >/dev/null
check "plot frames the stepper's 0.4 s transient: a horizon of at most 2 s" "/usr/bin/python3 - <<'PY'
import glob
rows = []
for f in sorted(glob.glob('fig/evaluation_data/*')):
    for line in open(f):
        p = line.replace(',', ' ').split()
        try: rows.append(float(p[0]))
        except (ValueError, IndexError): pass
assert rows and 0.5 <= max(rows) <= 2, max(rows) if rows else 'no data'
PY"

# ---- A box nobody gave is widened when the optimum is on its upper edge.
"$pidlab" tune --num 1 --den 1,2,1 --method multi-start --max-evals 300 --json > wide.json
"$pidlab" tune --num 1 --den 1,2,1 --method multi-start --max-evals 300 > wide.txt
"$pidlab" tune --num 1 --den 1,2,1 --method multi-start --max-evals 300 --bounds 0,15.5 --json > given_box.json
check "a search on the edge of the plant's box widens it tenfold, and says so; a given box is kept" "/usr/bin/python3 - <<'PY'
import json
j, g = json.load(open('wide.json')), json.load(open('given_box.json'))
w = j['box']['widened_from']
assert len(w) >= 1 and abs(w[0] - 15.5) < 0.01 and abs(j['box']['upper'] - 10 * w[-1]) < 1e-9 * j['box']['upper'], j['box']
assert 'widened_from' not in g['box'] and g['box']['upper'] == 15.5 and 'kp_hi' in g['at_bounds'], (g['box'], g['at_bounds'])
PY"
check "the text says so too" "grep -q '^box widened  *\[0, 15.5' wide.txt"

# ---- A PID that cannot be evaluated (an ideal derivative on relative degree
# 1 with dead time: every loop neutral) gets the best filtered PID, said in one line.
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method multi-start --derivative-filter-ratio 0 >neutral.txt 2>&1
check "an ideal derivative's neutral loop: exit 0 with the best filtered PID" "[ $? -eq 0 ]"
check "... and one line says so, with the flag" \
  "[ \$(grep -c '^fallback  *an ideal derivative makes every loop on this plant neutral (relative degree 1 with dead time): tuned the best filtered PID instead, tf = Td / 10 (--derivative-filter-ratio 10)' neutral.txt) -eq 1 ]"
"$pidlab" tune --num 1 --den 10,1 --delay 2 --method multi-start --derivative-filter-ratio 0 --max-evals 400 --json >neutral.json
"$pidlab" tune --spec neutral.json --json >neutral.again.json
check "its JSON: the fallback, a stable filtered loop, and an echo that reruns to the same gains" "/usr/bin/python3 - <<'PY'
import json
j, e = json.load(open('neutral.json')), json.load(open('neutral.again.json'))
assert j['fallback'].startswith('an ideal derivative makes every loop'), j.get('fallback')
assert j['stable'] and abs(j['gains']['tf'] - j['gains']['kd'] / (10 * j['gains']['kp'])) < 1e-12, j['gains']
assert e['gains'] == j['gains'] and e['fallback'] == j['fallback'], (e['gains'], j['gains'])
PY"

# ---- The sampled loop's filter is relative to its period: at least dt.
"$pidlab" tune --num 2 --den 60,1 --delay 8 --robust --loop sampled --dt 1 --json >robust_dt.json
check "--robust at dt = 1 s on the thermal model: tf = 1 s (Td/10 would be below dt), noise gain below 7" "/usr/bin/python3 - <<'PY'
import json
j = json.load(open('robust_dt.json'))
g = j['gains']
assert g['kd'] / (10 * g['kp']) < 1.0 and g['tf'] == 1.0, g
assert j['robustness']['noise_gain'] < 7, j['robustness']['noise_gain']
PY"
"$pidlab" tune --num 1 --den 1,1 --max-time-constant 0.001 --max-evals 300 >slow.txt 2>&1
check "no loop fast enough: --max-time-constant is named" \
  "grep -q 'probe points of the box are slower than --max-time-constant; what helps: raise --max-time-constant' slow.txt"

# ---- Bad knob values: exit 2, one line naming the value.
bad() {  # bad WHAT NEEDLE ARGS...
  local what=$1 needle=$2 said
  shift 2
  if said=$(bad_input_ok "$needle" "$pidlab" tune "$@"); then check "$what: $said" "true"; else check "$what: $said" "false"; fi
}
bad "--robustness 1" "1" --num 1 --den 10,1 --delay 2 --robustness 1
bad "--robustness 9" "9" --num 1 --den 10,1 --delay 2 --robustness 9
bad "--robustness 85 (deg)" "85" --num 1 --den 10,1 --delay 2 --robustness 85
bad "--crossover -1" "-1" --num 1 --den 10,1 --delay 2 --crossover -1
bad "--crossover with --response-time" "say the same thing twice" --num 1 --den 10,1 --delay 2 --crossover 1 --response-time 2
bad "--response-time -1" "-1" --num 1 --den 10,1 --delay 2 --response-time -1
bad "--tau-c -1" "-1" --num 1 --den 10,1 --delay 2 --method simc --tau-c -1
bad "--method migo without a filter" "filter" --num 1 --den 10,1 --delay 2 --method migo --horizon 100 \
  --sample-time 0.2 --derivative-filter-ratio 0

echo "passed $pass, failed $fail"
[[ $fail -eq 0 ]]
