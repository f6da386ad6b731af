#!/usr/bin/env bash
# pidlab identify on a record beyond --max-samples (docs/identify.md, "Long
# records"): a 200 000-row CSV of a first-order step with delay and noise,
# written here by python3 (seeded), finishes in under 20 s (the bound issue
# 59 sets; the bench has the figures), decimated by 20 to 10000 samples,
# saying so on stderr at once with its progress, in the text and in the
# JSON; the gain, time constant and delay within 3 % of the truth. Under
# --quiet stderr is empty; a bad --max-samples exits 2 with one line; a
# time constant too short for the decimated record is warned of.
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab="$1"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

# P1D Kp = 2, Tp1 = 40 s, Td = 5 s at dt = 0.01 s: a step at 100 s, noise 0.02.
/usr/bin/python3 - <<'PY'
import math, random
rng, kp, tau, td, dt, rows = random.Random(59), 2.0, 40.0, 5.0, 0.01, 200000
a, y = math.exp(-dt / tau), 0.0
with open('long.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(rows):
        t = k * dt
        f.write('%.2f,%g,%.6f\n' % (t, 1.0 if t >= 100.0 else 0.0, y + rng.gauss(0.0, 0.02)))
        y = a * y + kp * (1.0 - a) * (1.0 if t - td >= 100.0 - 1e-9 else 0.0)
PY

start=$(date +%s.%N)
"$pidlab" identify --csv long.csv --model p1d --u0 0 > text 2> err
status=$?
seconds=$(echo "$(date +%s.%N) - $start" | bc)
check "identify on 200 000 rows exits 0 in under 20 s ($seconds s)" \
  "[ $status -eq 0 ] && [ \$(echo '$seconds < 20' | bc) -eq 1 ]"
check "stderr says at once that the record is decimated by 20, naming --max-samples 10000" \
  "head -n 1 err | grep -q '200000 samples, more than --max-samples 10000: decimated by 20'"
check "stderr shows the fit's progress (starts done of planned)" \
  "grep -Eq '^pidlab identify: p1d: [0-9]+ of [0-9]+ starts, best cost' err"
check "the text says the record was decimated" \
  "grep -q '^record decimated by 20: 200000 samples to 10000 (--max-samples 10000)' text"
echo "figures: identify --model p1d on 200000 rows: $seconds s, $(wc -l < err) stderr lines"

"$pidlab" identify --csv long.csv --model p1d --u0 0 --json --quiet > json 2> quiet_err
check "--json --quiet exits 0 with an empty stderr" "[ $? -eq 0 ] && [ ! -s quiet_err ]"
/usr/bin/python3 - json > close <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
d, p = j['decimation'], {k: v['value'] for k, v in j['parameters'].items()}
ok = d == {'factor': 20, 'samples_read': 200000, 'samples': 10000, 'max_samples': 10000, 'start_samples': 1250} and j['samples'] == 10000
for name, truth in (('Kp', 2.0), ('Tp1', 40.0), ('Td', 5.0)):
    ok = ok and abs(p[name] - truth) <= 0.03 * truth
print('ok' if ok else 'no', d, p)
PY
check "the JSON's decimation is {factor 20, 200000 read, 10000 fitted, starts on 1250}; Kp, Tp1, Td within 3 % ($(cat close))" \
  "grep -q '^ok' close"

"$pidlab" identify --csv long.csv --model p1d --max-samples 5 > /dev/null 2> bad
check "--max-samples 5 exits 2 with one line naming the limit" \
  "[ $? -eq 2 ] && only_line_ok bad '--max-samples 5 must be in [100, 10000000]'"

# Tp1 = 0.03 s at dt = 1 ms, decimated by 20 to 0.02 s: the fit warns that
# Tp1 is under two of the decimated intervals.
/usr/bin/python3 - <<'PY'
import math, random
rng, kp, tau, dt, rows = random.Random(5), 2.0, 0.03, 0.001, 20000
a, y = math.exp(-dt / tau), 0.0
with open('fast.csv', 'w') as f:
    f.write('t,u,y\n')
    for k in range(rows):
        u = 1.0 if (k // 500) % 2 else 0.0
        f.write('%.3f,%g,%.6f\n' % (k * dt, u, y + rng.gauss(0.0, 0.02)))
        y = a * y + kp * (1.0 - a) * u
PY
"$pidlab" identify --csv fast.csv --model p1d --u0 0 --max-samples 1000 > /dev/null 2> fast_err
check "a time constant under two decimated intervals is warned of, naming the factor and the limit" \
  "[ $? -eq 0 ] && grep -q '^warning: Tp1 = .* s is under two intervals (0.02 s) of the record decimated by 20 from 20000 samples: .*max_samples (1000)' fast_err"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
