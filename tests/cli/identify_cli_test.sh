#!/usr/bin/env bash
# pidlab identify: a P1D record written by python3 from the closed-form step
# response (independent of DiscretePlant), its parameters recovered; the
# commands of docs/identify.md ("Identifying a model from a CSV") run as
# printed there; bad input exits 2 with one line.
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab="$1"
docs=$(cd "$(dirname -- "$0")/../../docs" && pwd)/identify.md
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

"$pidlab" identify --help > help
check "identify --help exits 0 and names its flags" \
  "[ $? -eq 0 ] && grep -q -- '--csv' help && grep -q -- '--model' help && grep -q -- '--json' help"

# P1D Kp = 2, Tp1 = 1.5 s, Td = 0.25 s (not a multiple of dt = 0.1 s), around
# u0 = 1, y0 = 3; columns out of order, one extra.
/usr/bin/python3 - <<'PY'
import math, random
kp, tp1, td, dt, n = 2.0, 1.5, 0.25, 0.1, 300
random.seed(3)
u, k = [0.0] * n, 5
while k < n:
    level, hold = random.uniform(-1, 1), random.randint(3, 15)
    for i in range(k, min(n, k + hold)): u[i] = level
    k += hold
def y(t, times=[j * dt for j in range(n)]):  # superposition of the delayed steps of u
    total, prev = 0.0, 0.0
    for j in range(n):
        s = t - (times[j] + td)
        if u[j] != prev and s > 0: total += (u[j] - prev) * kp * (1 - math.exp(-s / tp1))
        prev = u[j]
    return total
with open('step.csv', 'w') as f:
    f.write('u,t,note,y\n')
    for k in range(n): f.write('%.17g,%.17g,0,%.17g\n' % (u[k] + 1, k * dt, y(k * dt) + 3))
# The same input on a jittered grid: every interval dt (1 + U(-0.3, 0.3)).
random.seed(5)
tj = [0.0]
for k in range(1, n): tj.append(tj[-1] + dt * (1 + random.uniform(-0.3, 0.3)))
with open('jitter.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(n): f.write('%.17g,%.17g,%.17g\n' % (tj[k], u[k] + 1, y(tj[k], tj) + 3))
# The same record cut in motion: from the first sample c >= 40 after which u
# changes and before which it has held for more than the delay.
c = next(c for c in range(40, n - 1) if len(set(u[c - 4:c + 1])) == 1 and u[c + 1] != u[c])
with open('cut.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(c, n): f.write('%.17g,%.17g,%.17g\n' % (k * dt, u[k] + 1, y(k * dt) + 3))
PY
# A smooth input (a sum of sines, as a sampled chirp) through P2D Kp = 2,
# Tp1 = 1.5 s, Tp2 = 0.4 s, Td = 0.25 s with the input linear between samples:
# scipy's lsim with interp=True (a first-order hold) on a 0.05 s grid where
# the delay is 5 steps and the input is still linear.
/usr/bin/python3 - <<'PY'
import numpy as np
from scipy import signal
dt, n, fine = 0.1, 300, 2
t = np.arange(n) * dt
u = np.sin(0.7 * t) + 0.5 * np.sin(2.3 * t + 1.0) + 0.25 * np.sin(5.1 * t)
t_fine = np.arange((n - 1) * fine + 1) * dt / fine
du_fine = np.interp(t_fine, t, u - u[0])
delayed = np.concatenate([np.zeros(5), du_fine[:-5]])
_, y, _ = signal.lsim(signal.lti([2.0], np.polymul([1.5, 1.0], [0.4, 1.0])), delayed, t_fine, interp=True)
with open('smooth.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(n): f.write('%.17g,%.17g,%.17g\n' % (t[k], u[k] + 1, y[k * fine] + 3))
PY
# The same P1D from rest at u = 1 with 2 % of y (6 samples, seeded) dropped
# out to y + 10 (docs/identify.md, "Robust losses for dropouts"); and from
# rest at u = 0 under a +-1 PRBS whose first level is +1 ("A record that
# starts at rest under a nonzero input").
/usr/bin/python3 - <<'PY'
import math, random
kp, tp1, td, dt, n = 2.0, 1.5, 0.25, 0.1, 300
random.seed(3)
u, k = [0.0] * n, 5
while k < n:
    level, hold = random.uniform(-1, 1), random.randint(3, 15)
    for i in range(k, min(n, k + hold)): u[i] = level
    k += hold
def y(t):  # superposition of the delayed steps of u from rest at u = 0
    total, prev = 0.0, 0.0
    for j in range(n):
        s = t - (j * dt + td)
        if u[j] != prev and s > 0: total += (u[j] - prev) * kp * (1 - math.exp(-s / tp1))
        prev = u[j]
    return total
random.seed(7)
bad = sorted(random.sample(range(n), n // 50))
with open('dropouts.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(n): f.write('%.17g,%.17g,%.17g\n' % (k * dt, u[k] + 1, y(k * dt) + 3 + (10 if k in bad else 0)))
with open('dropouts.txt', 'w') as f: f.write(' '.join(map(str, bad)))
random.seed(11)
k, level = 0, 1.0
while k < n:
    hold = random.randint(3, 12)
    for i in range(k, min(n, k + hold)): u[i] = level
    k += hold
    level = -level
with open('prbs_rest.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(n): f.write('%.17g,%.17g,%.17g\n' % (k * dt, u[k], y(k * dt) + 3))
PY

# The commands of docs/identify.md's section, as written there (its ```bash block);
# the real records of tests/data/identify beside the written ones.
cp "$(dirname -- "$docs")"/../tests/data/identify/*.csv .
n_docs=0
while IFS= read -r cmd; do
  n_docs=$((n_docs + 1))
  (pidlab() { "$pidlab" "$@"; }; eval "$cmd") > docs.out 2>&1
  check "docs/identify.md: $cmd" "[ $? -eq 0 ]"
done < <(awk '/^```bash/{on=1; next} /^```/{on=0} on && /^pidlab identify /' "$docs")
check "docs/identify.md has 9 identify commands (found $n_docs)" "[ $n_docs -eq 9 ]"
pidlab() { "$pidlab" "$@"; }
pidlab identify --csv tclab_step.csv --model p1d --u0 0 --json > tclab.json 2> tclab.err
check "the TCLab step test is a step from --u0 0: fitted, a fit above 95 %" \
  "[ $? -eq 0 ] && /usr/bin/python3 -c 'import json,sys; j=json.load(open(\"tclab.json\")); sys.exit(0 if j[\"fit_percent\"] > 95 else 1)'"
"$pidlab" identify --csv tclab_step.csv --model p1d > out 2> err
check "the TCLab step test without --u0 exits 2 with one line saying to give it" \
  "[ $? -eq 2 ] && only_line_ok err 'give --u0'"
pidlab() { "$pidlab" "$@"; }
pidlab identify --csv step.csv --model p1d > table 2> err
check "identify --csv step.csv --model p1d exits 0 with the table" \
  "[ $? -eq 0 ] && grep -q '^Kp  *2 ' table && grep -q '^Tp1  *1.5 ' table && grep -q '^Td  *0.25 ' table && grep -q 'starts reached the best cost' table"
pidlab identify --csv step.csv --model p1d --json > p1d.json 2> err
check "identify --json exits 0" "[ $? -eq 0 ] && [ ! -s err ]"
check "the JSON: Kp, Tp1, Td within 1e-6 relative, fit > 99.99 %, every key" "/usr/bin/python3 - p1d.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
for key in ('model', 'parameters', 'transfer_function', 'fit_percent', 'aic', 'aic_form', 'cost', 'samples', 'dt_s',
            'u0', 'y0', 'starts', 'starts_at_best', 'covariance'): assert key in j, key
p = j['parameters']
for name, want in (('Kp', 2.0), ('Tp1', 1.5), ('Td', 0.25)):
    assert abs(p[name]['value'] - want) <= 1e-6 * want, (name, p[name])
    assert 'standard_error' in p[name], name
assert j['model'] == 'p1d' and j['fit_percent'] > 99.99 and j['samples'] == 300, j
assert j['u0'] == 1 and abs(j['y0'] - 3) < 1e-9 and j['y0_estimated'] and abs(j['dt_s'] - 0.1) < 1e-12, j
assert 1 <= j['starts_at_best'] <= j['starts'] == 16 + j['arx_start'], j
tf = j['transfer_function']
assert abs(tf['num'][0] - 2) < 1e-6 and abs(tf['den'][0] - 1.5) < 1e-6 and tf['den'][1] == 1, tf
assert abs(tf['delay_s'] - 0.25) < 1e-6, tf
PY"
check "step.csv, at rest under its first input u = 1, keeps u0 = u[0] against u0 = 0 by AIC" "/usr/bin/python3 - p1d.json <<'PY'
import json, sys
o = json.load(open(sys.argv[1]))['operating_point']
assert o['u0'] == 1 and o['source'].startswith('at rest under its first input u[0] = 1'), o
assert [h['u0'] for h in o['hypotheses']] == [1, 0] and o['hypotheses'][0]['aic'] < o['hypotheses'][1]['aic'], o
PY"
pidlab identify --csv prbs_rest.csv --model p1d --json > prbs.json 2> err
check "prbs_rest.csv without --u0: at rest at u = 0 chosen by AIC, Kp, Tp1, Td within 1e-6" "[ $? -eq 0 ] && /usr/bin/python3 - prbs.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j['u0'] == 0 and j['operating_point']['source'].startswith('at rest at u = 0'), j['operating_point']
for name, want in (('Kp', 2.0), ('Tp1', 1.5), ('Td', 0.25)):
    assert abs(j['parameters'][name]['value'] - want) <= 1e-6 * want, (name, j['parameters'][name])
PY"
pidlab identify --csv prbs_rest.csv --model p1d > table 2> err
check "the table says which rest was used" "[ $? -eq 0 ] && grep -q '^u0 0: at rest at u = 0 before the record (AIC' table"
pidlab identify --csv dropouts.csv --model p1d --json > l2.json 2> err
pidlab identify --csv dropouts.csv --model p1d --loss cauchy --json > cauchy.json 2> err
check "dropouts.csv: --loss cauchy within 1 % of Kp, Tp1, Td, l2 more than 5 % off one; the dropouts listed" \
  "/usr/bin/python3 - l2.json cauchy.json dropouts.txt <<'PY'
import json, sys
l2, cauchy = (json.load(open(f)) for f in sys.argv[1:3])
bad = [int(k) for k in open(sys.argv[3]).read().split()]
truth = {'Kp': 2.0, 'Tp1': 1.5, 'Td': 0.25}
def worst(j): return max(abs(j['parameters'][k]['value'] / v - 1) for k, v in truth.items())
print('l2 %.3g, cauchy %.3g' % (worst(l2), worst(cauchy)))
assert worst(cauchy) < 0.01 and worst(l2) > 0.05
loss = cauchy['loss']
assert loss['name'] == 'cauchy' and loss['scale'] > 0 and 'l2 fit' in loss['scale_source'], loss
assert loss['downweighted']['samples'] == bad and loss['downweighted']['count'] == len(bad) == 6, loss
assert l2['loss']['name'] == 'l2' and l2['loss']['scale'] is None and l2['loss']['downweighted']['count'] == 0
PY"
pidlab identify --csv dropouts.csv --model p1d --loss huber --loss-scale 0.05 > table 2> err
check "--loss huber --loss-scale 0.05: the table names the loss, its given scale and the 6 samples" \
  "[ $? -eq 0 ] && grep -q '^loss huber, scale 0.05 (given); 6 samples down-weighted' table"
for args in "--loss tukey:--loss 'tukey'" "--loss cauchy --loss-scale 0:--loss-scale '0'" \
            "--loss cauchy --loss-scale abc:--loss-scale 'abc'" "--loss-scale 2:--loss-scale 2 applies to"; do
  "$pidlab" identify --csv dropouts.csv --model p1d ${args%%:*} > out 2> err
  check "identify ${args%%:*} exits 2 with one line naming it" "[ $? -eq 2 ] && only_line_ok err \"${args#*:}\""
done
check "identify --help names --loss and --loss-scale" "grep -q -- '--loss ' help && grep -q -- '--loss-scale' help"
pidlab identify --csv step.csv --model auto --json > auto.json 2> err
check "--model auto fits every kind and chooses p1d by AIC, saying why" "[ $? -eq 0 ] && /usr/bin/python3 - auto.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
a = j['auto']
assert a['chosen'] == 'p1d' == j['model'], a
assert [c['model'] for c in a['candidates']] == ['p1d', 'p2d', 'p2du', 'p1di', 'p2dz'], a
best = min(c['aic'] for c in a['candidates'] if c['ok'])
assert j['aic'] <= best + 2 and 'AIC' in a['reason'], a
PY"
pidlab identify --csv step.csv --model p2dz --out p2dz.json > p2dz.txt 2> err
check "--model p2dz fits Kp (1 + Tz s) e^(-Td s)/((1 + Tp1 s)(1 + Tp2 s)), and its file is a plant" \
  "[ $? -eq 0 ] && grep -q '^Tz ' p2dz.txt && grep -q 'Kp (1 + Tz s)' p2dz.txt && pidlab evaluate --model p2dz.json --gains 0.5,0.4,0 --loop sampled --json > p2dz_eval.json"
pidlab identify --csv step.csv --model p1d --plot fit.png > /dev/null 2> err
check "--plot draws a PNG of the fit" "[ $? -eq 0 ] && head -c 4 fit.png | grep -q PNG"
pidlab identify --csv step.csv --model p1d --log x.lcmlog > out 2> err
check "--csv with --log exits 2 with one line" "[ $? -eq 2 ] && only_line_ok err 'exactly one of --csv FILE and --log FILE'"
pidlab identify --csv step.csv --model p1d --episode 3 > out 2> err
check "--episode without --log exits 2 with one line" "[ $? -eq 2 ] && only_line_ok err '--episode applies to --log only'"
pidlab identify --log missing.lcmlog --model p1d > out 2> err
check "a missing log exits 2 with one line" "[ $? -eq 2 ] && only_line_ok err 'missing.lcmlog'"
pidlab identify --csv step.csv --model p1d --u0 inf > out 2> err
check "--u0 inf exits 2 with one line" "[ $? -eq 2 ] && only_line_ok err '--u0'"
pidlab identify --csv step.csv --model p2d --out model.json > /dev/null 2> err
check "--out writes the JSON object" \
  "[ $? -eq 0 ] && /usr/bin/python3 -c 'import json; j = json.load(open(\"model.json\")); assert j[\"model\"] == \"p2d\"'"

# A general transfer function (docs/identify.md, "A general transfer function"):
# tf.csv from scipy's exact response of (0.5 s + 1) e^(-0.25 s) / (s^2 + 1.2 s
# + 0.8) to a held input (lsim on a 0.05 s grid, on which both dt = 0.1 s and
# the delay fall, holding u between its points).
/usr/bin/python3 - <<'PY'
import numpy as np
from scipy import signal
dt, n, fine = 0.1, 400, 2
rng = np.random.default_rng(3)
u = np.repeat(rng.uniform(-1, 1, n // 8), 8)
u[:5] = 0.0
t_fine = np.arange(n * fine) * dt / fine
u_fine = np.repeat(u, fine)
delayed = np.concatenate([np.zeros(5), u_fine[:-5]])  # 0.25 s = 5 fine steps
_, y, _ = signal.lsim(signal.lti([0.5, 1.0], [1.0, 1.2, 0.8]), delayed, t_fine, interp=False)
with open('tf.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(n): f.write('%.17g,%.17g,%.17g\n' % (k * dt, u[k] + 1, y[k * fine] + 3))
PY
section=$(awk '/^## A general transfer function/{on=1; next} on && /^## /{on=0} on' "$docs")
n_tf=0
while IFS= read -r cmd; do
  n_tf=$((n_tf + 1))
  eval "$cmd" > docs.out 2> docs.err
  check "docs/identify.md: $cmd" "[ $? -eq 0 ] || { cat docs.err; false; }"
done < <(awk '/^```sh/{on=1; next} /^```/{on=0} on && /^pidlab /' <<<"$section")
check "the tf section has 3 commands (found $n_tf)" "[ $n_tf -eq 3 ]"
pidlab identify --csv tf.csv --model tf --poles 2 --zeros 1 --json > tf.json 2> err
check "identify --model tf --poles 2 --zeros 1 --json recovers b0 b1 a0 a1 Td within 1e-6 relative" \
  "[ $? -eq 0 ] && /usr/bin/python3 - tf.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert (j['model'], j['poles'], j['zeros']) == ('tf', 2, 1), j
p = j['parameters']
assert sorted(p) == ['Td', 'a0', 'a1', 'b0', 'b1'], p
for name, want in (('b0', 1.0), ('b1', 0.5), ('a0', 0.8), ('a1', 1.2), ('Td', 0.25)):
    assert abs(p[name]['value'] - want) <= 1e-6 * want, (name, p[name])
assert j['fit_percent'] > 99.99, j['fit_percent']
tf = j['transfer_function']
assert len(tf['num']) == 2 and tf['den'][0] == 1 and len(tf['den']) == 3, tf
assert abs(tf['delay_s'] - 0.25) < 1e-6, tf
assert len(j['covariance']['matrix']) == 5 or not j['covariance']['ok'], j['covariance']
PY"
pidlab identify --csv tf.csv --model tf --poles 2 --zeros 1 > tf.txt 2> err
check "the tf table names the formula and every coefficient" \
  "[ $? -eq 0 ] && grep -q '(b1 s + b0) e^(-Td s) / (s^2 + a1 s + a0)' tf.txt && grep -q '^a1 ' tf.txt && grep -q '^b1 ' tf.txt"
check "the tf model file is a plant whose Monte Carlo draws from its covariance" \
  "pidlab evaluate --model tf_model.json --gains 0.5,0.4,0 --loop sampled --monte-carlo 5 --json > tf_eval.json && grep -q \"identified model's parameter covariance\" tf_eval.json"
for case in "--model tf|--model tf needs --poles N" "--model tf --poles 7|--poles 7 must be in 1..6" \
            "--model tf --poles 0|--poles 0 must be in 1..6" \
            "--model tf --poles 2 --zeros 2|--zeros 2 must be in 0..1 (fewer than --poles 2)" \
            "--model tf --poles 2 --zeros -1|--zeros -1 must be in 0..1" \
            "--model p2d --poles 2|--poles 2 applies to --model tf only" \
            "--model auto --zeros 1|--zeros 1 applies to --model tf only"; do
  args=${case%%|*} needle=${case#*|}
  "$pidlab" identify --csv tf.csv $args > out 2> err
  check "identify $args exits 2 with one line naming '$needle'" \
    "[ $? -eq 2 ] && only_line_ok err \"$needle\" && [ ! -s out ]"
done

# Non-uniform sampling: said in one line of the table and in the JSON's
# sampling; the parameters come back from the exact response interval by
# interval.
pidlab identify --csv jitter.csv --model p1d > table 2> err
check "identify --csv jitter.csv exits 0 and says the sampling is non-uniform" \
  "[ $? -eq 0 ] && [ ! -s err ] && grep -q '^sampling is non-uniform (intervals 0.07[0-9]* to 0.12[0-9]* s, dt above is the mean): the exact response interval by interval is used$' table"
pidlab identify --csv jitter.csv --model p1d --json > jitter.json 2> err
check "the jittered record's JSON: sampling {uniform false, min, max}, Kp, Tp1, Td within 1e-6 relative" \
  "[ $? -eq 0 ] && /usr/bin/python3 - jitter.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
s = j['sampling']
assert s['uniform'] is False and 0.07 <= s['min_interval_s'] < 0.075 and 0.125 < s['max_interval_s'] <= 0.13, s
for name, true in (('Kp', 2.0), ('Tp1', 1.5), ('Td', 0.25)):
    assert abs(j['parameters'][name]['value'] - true) <= 1e-6 * true, (name, j['parameters'][name])
PY"
pidlab identify --csv step.csv --model p1d --json > uniform.json 2> err
check "a uniform record's JSON says sampling {uniform true}" \
  "[ $? -eq 0 ] && /usr/bin/python3 -c \"import json; s = json.load(open('uniform.json'))['sampling']; assert s['uniform'] is True and abs(s['min_interval_s'] - 0.1) < 1e-12 and abs(s['max_interval_s'] - 0.1) < 1e-12, s\""

# Intersample behaviour and the initial condition (docs/identify.md, "Intersample
# behaviour and the initial condition").
pidlab identify --csv smooth.csv --model p2d --intersample foh --json > foh.json 2> err
check "--intersample foh recovers scipy's first-order-hold P2D within 1e-6, and says it" \
  "[ $? -eq 0 ] && /usr/bin/python3 - foh.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j['intersample'] == 'foh' and j['initial_condition'] == 'zero', j
for name, true in (('Kp', 2.0), ('Tp1', 1.5), ('Tp2', 0.4), ('Td', 0.25)):
    assert abs(j['parameters'][name]['value'] - true) <= 1e-6 * true, (name, j['parameters'][name])
PY"
pidlab identify --csv smooth.csv --model p2d > table 2> err
check "the same record held (zoh) is misfitted: fit below 99.99 %" \
  "[ $? -eq 0 ] && awk '/^fit / { exit !(\$2 < 99.99) }' table"
pidlab identify --csv smooth.csv --model p2d --intersample foh --initial-condition estimate --u0 estimate --y0 3 --json > all.json 2> err
check "README's row: foh, an estimated state and u0 together run, and find Kp within 1e-4" \
  "[ $? -eq 0 ] && /usr/bin/python3 -c \"import json; j = json.load(open('all.json')); assert abs(j['parameters']['Kp']['value'] - 2) < 2e-4 and j['u0_estimated'], j['parameters']\""
pidlab identify --csv cut.csv --model p1d --initial-condition estimate --json > cut.json 2> err
check "--initial-condition estimate recovers P1D from a record cut in motion within 1e-6" \
  "[ $? -eq 0 ] && /usr/bin/python3 - cut.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j['initial_condition'] == 'estimate' and len(j['initial_state']) == 1 and abs(j['initial_state'][0]) > 1e-3, j
for name, true in (('Kp', 2.0), ('Tp1', 1.5), ('Td', 0.25)):
    assert abs(j['parameters'][name]['value'] - true) <= 1e-6 * true, (name, j['parameters'][name])
PY"
pidlab identify --csv cut.csv --model p1d --initial-condition estimate > table 2> err
check "the table says the hold and the initial condition" \
  "[ $? -eq 0 ] && grep -q '^input zoh between samples, initial condition estimate$' table"
for case in "--intersample linear|--intersample 'linear' must be zoh or foh" \
            "--initial-condition rest|--initial-condition 'rest' must be zero, steady-state or estimate"; do
  args=${case%%|*} needle=${case#*|}
  "$pidlab" identify --csv step.csv --model p1d $args > out 2> err
  check "identify $args exits 2 with one line naming it" "[ $? -eq 2 ] && only_line_ok err \"$needle\" && [ ! -s out ]"
done

pidlab identify --csv step.csv --model p1d --u0 estimate --y0 3 --json > u0.json 2> err
check "--u0 estimate --y0 3 fits u0 = 1 (the record's rest) with the model, and says it" \
  "[ $? -eq 0 ] && /usr/bin/python3 -c \"import json; j = json.load(open('u0.json')); assert j['u0_estimated'] is True and abs(j['u0'] - 1) < 1e-6 and j['u0_standard_error'] is not None and abs(j['parameters']['Kp']['value'] - 2) < 2e-6, j\""
"$pidlab" identify --csv step.csv --model p1d --u0 abc > out 2> err
check "--u0 abc exits 2 with one line naming it" "[ $? -eq 2 ] && only_line_ok err \"--u0 'abc' must be a finite number or 'estimate'\""
pidlab identify --log missing.lcmlog --model p1d --intersample foh > out 2> err
check "--intersample foh on a log exits 2: the plant holds its input" \
  "[ $? -eq 2 ] && only_line_ok err \"--intersample foh: a log's input u + n is held\""

# Bad input: exit 2, one line naming the flag, file, column, row or value.
sed '1s/^u,t,note,y/u,time,note,y/' step.csv > nocolumn.csv
awk 'NR == 40 { $0 = "0.5,3.8,0,abc" } { print }' step.csv > badcell.csv
awk 'NR == 40 { $0 = "nan,3.8,0,3" } { print }' step.csv > nan.csv
head -n 15 step.csv > short.csv
awk -F, 'NR == 1 { print; next } { print "1," $2 ",0," $4 }' step.csv > constant.csv
for case in "nocolumn.csv --model p1d|names no column t" "badcell.csv --model p1d|row 40, column y: 'abc'" \
            "nan.csv --model p1d|not finite: u at sample 38" "short.csv --model p1d|too short: 14 samples" \
            "constant.csv --model p1d|constant input" "step.csv --model p9d|--model 'p9d'" \
            "missing.csv --model p1d|cannot be read"; do
  args=${case%%|*} needle=${case#*|}
  "$pidlab" identify --csv $args > out 2> err
  check "identify --csv $args exits 2 with one line naming '$needle'" \
    "[ $? -eq 2 ] && only_line_ok err \"$needle\" && [ ! -s out ]"
done
"$pidlab" identify --csv step.csv --model p1d --starts 0 > out 2> err
check "--starts 0 exits 2 with one line" "[ $? -eq 2 ] && only_line_ok err '--starts 0'"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
