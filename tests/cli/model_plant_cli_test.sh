#!/usr/bin/env bash
# The identified model as a plant (docs/identify.md, "The identified model as
# a plant"): a noisy P1D record identified with --out model.json, then
# `evaluate`, `tune` and `plot` on --model model.json (the section's commands
# as printed there), the same IAE as the custom plant of its num/den/delay,
# the spec echo run again, draws from the covariance, the fallback to the
# coefficients, and bad model files (exit 2, one line).
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab="$1"
docs=$(cd "$(dirname -- "$0")/../../docs" && pwd)/identify.md
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
pidlab() { "$pidlab" "$@"; }

# P1D Kp = 2, Tp1 = 1.5 s, Td = 0.25 s, a seeded random input, y with seeded
# Gaussian noise (sigma 0.05) so that the covariance is not zero.
/usr/bin/python3 - <<'PY'
import math, random
kp, tp1, td, dt, n = 2.0, 1.5, 0.25, 0.1, 300
random.seed(3)
u, k = [0.0] * n, 5
while k < n:
    level, hold = random.uniform(-1, 1), random.randint(3, 15)
    for i in range(k, min(n, k + hold)): u[i] = level
    k += hold
def y(t):
    total, prev = 0.0, 0.0
    for j in range(n):
        s = t - (j * dt + td)
        if u[j] != prev and s > 0: total += (u[j] - prev) * kp * (1 - math.exp(-s / tp1))
        prev = u[j]
    return total
noise = random.Random(5)
with open('step.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(n): f.write('%.17g,%.17g,%.17g\n' % (k * dt, u[k], y(k * dt) + noise.gauss(0, 0.05)))
PY

# The commands of the section, as written there (its ```sh block).
section=$(awk '/^## The identified model as a plant/{on=1; next} on && /^## /{on=0} on' "$docs")
n_docs=0
while IFS= read -r cmd; do
  n_docs=$((n_docs + 1))
  eval "$cmd" > docs.out 2> docs.err
  check "docs/identify.md: $cmd" "[ $? -eq 0 ] || { cat docs.err; false; }"
done < <(awk '/^```sh/{on=1; next} /^```/{on=0} on && /^pidlab /' <<<"$section")
check "the section has 4 commands (found $n_docs)" "[ $n_docs -eq 4 ]"
check "the section's figure was drawn" "[ -s figures/evaluation.png ]"
[ -s model.json ] || pidlab identify --csv step.csv --model p1d --out model.json > /dev/null

# --model FILE and --plant model:FILE: the same evaluation as the custom plant
# of the file's num/den/delay, bit for bit; the echo is "model:FILE".
G=(--gains 0.5,0.4,0 --loop sampled)
pidlab evaluate --model model.json "${G[@]}" --json > by_model.json 2> err
check "evaluate --model exits 0" "[ $? -eq 0 ] && [ ! -s err ]"
pidlab evaluate --plant model:model.json "${G[@]}" --json > by_plant.json 2> err
read -r num den delay < <(/usr/bin/python3 -c '
import json; t = json.load(open("model.json"))["transfer_function"]
print(",".join(repr(c) for c in t["num"]), ",".join(repr(c) for c in t["den"]), repr(t["delay_s"]))')
pidlab evaluate --plant custom --num "$num" --den "$den" --delay "$delay" "${G[@]}" --json > by_custom.json
check "--model, --plant model:FILE and the custom num/den/delay give the same IAE, bit for bit" "/usr/bin/python3 - <<'PY'
import json
a, b, c = (json.load(open(f)) for f in ('by_model.json', 'by_plant.json', 'by_custom.json'))
assert a['iae'] == b['iae'] == c['iae'] and a['iae'] > 0, (a['iae'], b['iae'], c['iae'])
assert a['spec']['plant'] == b['spec']['plant'] == 'model:model.json', a['spec']['plant']
assert a['spec']['model'] == '' and a['spec']['delay'] == 0 and a['spec']['num'] == [], a['spec']
PY"
pidlab evaluate --spec by_model.json --json > rerun.json
check "the echoed spec runs again to the same JSON" "cmp -s by_model.json rerun.json"
# docs/spec.md: another result's spec, run on the model (its loop: eq. (4)'s
# time scale, which the double integrator's result echoes).
pidlab evaluate --plant double_integrator "${G[@]}" --json > other.json
pidlab evaluate --spec other.json --model model.json --json > other_on_model.json 2> err
pidlab evaluate --model model.json "${G[@]}" --horizon 25 --sample-time 0.05 --json > by_model_eq4.json
check "--spec result.json --model model.json runs the result's loop on the model" "cmp -s by_model_eq4.json other_on_model.json"

# Draws from the covariance: evaluate --monte-carlo and tune --robust-samples.
pidlab evaluate --model model.json "${G[@]}" --monte-carlo 20 --seed 3 --json > mc.json 2> err
check "evaluate --monte-carlo draws from the covariance, the model's delay included" "/usr/bin/python3 - <<'PY'
import json
m = json.load(open('mc.json'))['monte_carlo']
assert m['perturbed'] == \"identified model's parameter covariance\", m
assert m['samples'] == 20 and m['stable'] == 20 and m['redrawn'] == 0 and m['spread'] is None, m
assert m['iae']['min'] < m['iae']['max'], m
PY"
pidlab evaluate --model model.json "${G[@]}" --monte-carlo 20 --seed 3 > mc.txt
check "the table says where the draws come from" \
  "grep -q \"monte carlo      20 plants from the identified model's parameter covariance (0 redrawn), seed 3\" mc.txt"
pidlab tune --model model.json --loop sampled --horizon 10 --robust-samples 8 --seed 1 --max-evals 80 \
  --refine none --json > tune.json 2> err
check "tune --model --robust-samples 8 draws the robust set from the covariance" "/usr/bin/python3 - <<'PY'
import json
j = json.load(open('tune.json'))
r = j['robust_set']
assert r['perturbed'] == \"identified model's parameter covariance\" and r['size'] == 9 and r['spread'] is None, r
assert j['stable'] is True and j['spec']['plant'] == 'model:model.json', j['spec']
PY"
pidlab tune --spec tune.json --json > tune_rerun.json
check "the tuning's echo runs again to the same gains" "/usr/bin/python3 - <<'PY'
import json
a, b = json.load(open('tune.json')), json.load(open('tune_rerun.json'))
assert a['gains'] == b['gains'] and a['spec'] == b['spec'], (a['gains'], b['gains'])
PY"

# A model whose covariance is not ok: the coefficients within --spread, said so.
/usr/bin/python3 - <<'PY'
import json
j = json.load(open('model.json'))
j['covariance'] = {'ok': False, 'message': 'the Jacobian is rank deficient', 'matrix': []}
json.dump(j, open('nocov.json', 'w'))
PY
pidlab evaluate --model nocov.json "${G[@]}" --monte-carlo 5 --spread 5% > nocov.txt 2> err
check "without a covariance the coefficients are drawn within --spread, and the output says why" \
  "[ $? -eq 0 ] && grep -q \"transfer-function coefficients (the identified model's covariance is not ok: the Jacobian is rank deficient) within +/-5 %\" nocov.txt"

# Bad input: exit 2, one line naming the file (or flag) and the reason.
printf '{"model": ' > notjson.json
/usr/bin/python3 - <<'PY'
import json
good = json.load(open('model.json'))
def write(name, change):
    j = json.loads(json.dumps(good)); change(j); json.dump(j, open(name, 'w'))
write('nokey.json', lambda j: j.pop('transfer_function'))
write('badnumber.json', lambda j: j['parameters']['Kp'].update(value='x'))
write('badkind.json', lambda j: j.update(model='p3d'))
write('badshape.json', lambda j: j['covariance'].update(matrix=[[1, 0], [0, 1]]))
write('badmodel.json', lambda j: j['parameters']['Tp1'].update(value=-1))
# The parameters and the transfer function must agree (issue 59): an edited
# Kp (zero, subnormal, ten times), Tp1 or Td, or an edited delay, is refused.
for name, v in (('kp0', 0.0), ('kpsub', 5e-324), ('kp50', 10 * good['parameters']['Kp']['value'])):
    write(name + '.json', lambda j, v=v: j['parameters']['Kp'].update(value=v))
write('tp1.json', lambda j: j['parameters']['Tp1'].update(value=2 * good['parameters']['Tp1']['value']))
write('td.json', lambda j: j['parameters']['Td'].update(value=good['parameters']['Td']['value'] + 1))
write('delay.json', lambda j: j['transfer_function'].update(delay_s=good['transfer_function']['delay_s'] + 1))
PY
for case in "missing.json|cannot be read" \
            "notjson.json|is not valid JSON" \
            "nokey.json|has no key \"transfer_function\"" \
            "badnumber.json|\"parameters.Kp.value\" \"x\" is not a number" \
            "badkind.json|\"model\" \"p3d\" must be p1d|p2d|p2du|p1di" \
            "badshape.json|\"covariance.matrix\" must be 3 x 3 (Kp, Tp1, Td)" \
            "badmodel.json|is not a valid p1d model: Tp1 -1 s must be > 0" \
            "kp0.json|\"transfer_function.num\" disagrees with \"parameters\"" \
            "kpsub.json|\"transfer_function.num\" disagrees with \"parameters\"" \
            "kp50.json|\"transfer_function.num\" disagrees with \"parameters\"" \
            "tp1.json|\"transfer_function.num\" disagrees with \"parameters\"" \
            "td.json|\"transfer_function.delay_s\"" \
            "delay.json|disagrees with \"parameters.Td\""; do
  file=${case%%|*} needle=${case#*|}
  pidlab evaluate --model "$file" "${G[@]}" > out 2> err
  check "evaluate --model $file exits 2 with one line naming '$needle'" \
    "[ $? -eq 2 ] && only_line_ok err '$needle' && grep -q \"$file\" err && [ ! -s out ]"
done
pidlab evaluate --model model.json "${G[@]}" --monte-carlo 5 --spread 20% > out 2> err
check "--spread on a model with a covariance exits 2 naming why" \
  "[ $? -eq 2 ] && only_line_ok err '--spread 0.2: --plant' && grep -q 'drawn from its parameter covariance' err"
pidlab tune --model model.json --loop sampled --robust-samples 4 --robust-spread 20% > out 2> err
check "--robust-spread on a model with a covariance exits 2" "[ $? -eq 2 ] && only_line_ok err '--robust-spread 0.2'"
pidlab evaluate --model model.json --delay 0.1 "${G[@]}" > out 2> err
check "--delay next to a model exits 2" "[ $? -eq 2 ] && only_line_ok err 'has its own dead time'"
pidlab evaluate --model model.json --plant oscillator "${G[@]}" > out 2> err
check "--model next to another --plant exits 2" "[ $? -eq 2 ] && only_line_ok err \"--model 'model.json' cannot be combined with --plant 'oscillator'\""
pidlab plot --model badkind.json --gains 1,1,0 --out figs > out 2> err
check "plot --model with a bad file exits 2" "[ $? -eq 2 ] && only_line_ok err 'p3d'"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
