#!/usr/bin/env bash
# Every --model of pidlab identify on the 200 000-row record of
# identify_long_cli_test.sh (P1D Kp = 2, Tp1 = 40 s, Td = 5 s, dt = 0.01 s,
# noise 0.02, seeded) at the default --max-samples (docs/identify.md, "Long
# records"): each exits 0 within a 120 s guard against an unbounded fit (the
# 4 min 20 s of issue 59; the times are printed, and measured by
# bench/identify_long_bench.sh: at load 3.4 on 2 cores 0.3 to 9.7 s, auto the
# longest, docs/benchmarks.md; a timed test would fail under -j2), saying on stderr's first line that the record was decimated by 20 and its
# starts ran on 1250 samples (a TF's on 2500), with its progress after it;
# the JSON's decimation has start_samples so; the gain (a TF's b0 / a0) within 3 %
# of the truth for every kind but p1di (an integrator: no finite gain).
set -uo pipefail
pidlab="$1"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

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

figures=""
for model in p1d p2d p2du p1di p2dz tf auto; do
  extra=(); starts=1250; [ "$model" = tf ] && extra=(--poles 2) && starts=2500
  start=$(date +%s.%N)
  "$pidlab" identify --csv long.csv --model "$model" "${extra[@]}" --u0 0 --json > "$model.json" 2> "$model.err"
  status=$?
  seconds=$(echo "$(date +%s.%N) - $start" | bc)
  figures="$figures $model $(printf '%.1f' "$seconds") s;"
  check "$model exits 0 within the 120 s guard ($seconds s)" "[ $status -eq 0 ] && [ \$(echo '$seconds < 120' | bc) -eq 1 ]"
  check "$model: stderr's first line says decimated by 20, the starts on $starts samples" \
    "head -n 1 $model.err | grep -q '200000 samples, more than --max-samples 10000: decimated by 20 .* its starts on $starts samples\$'"
  check "$model: its progress follows" "grep -Eq '^pidlab identify: [a-z0-9]+: [0-9]+ of [0-9]+ starts, best cost' $model.err"
  /usr/bin/python3 - "$model.json" "$model" "$starts" > "$model.close" <<'PY'
import json, sys
j, model = json.load(open(sys.argv[1])), sys.argv[2]
d, p = j['decimation'], {k: v['value'] for k, v in j['parameters'].items()}
ok = d == {'factor': 20, 'samples_read': 200000, 'samples': 10000, 'max_samples': 10000, 'start_samples': int(sys.argv[3])}
gain = p['b0'] / p['a0'] if model == 'tf' else p['Kp']
ok = ok and (model == 'p1di' or abs(gain - 2.0) <= 0.03 * 2.0)
print('ok' if ok else 'no', 'gain %.6g' % gain, d)
PY
  check "$model: the JSON's decimation has start_samples $starts; the gain within 3 % ($(cat "$model.close"))" \
    "grep -q '^ok' $model.close"
done
echo "figures:$figures"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
