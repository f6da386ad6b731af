#!/usr/bin/env bash
# pidlab tune from the command line: JSON keys, --trace, bad input.
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab="$1"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

"$pidlab" tune --plant linear --method multi-start --json --trace "$tmp/trace.csv" > "$tmp/out.json" 2>"$tmp/err"
check "tune --json exits 0" "[ $? -eq 0 ]"
check "tune --json has the documented keys" "python3 - \"$tmp/out.json\" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
for k in ['plant', 'method', 'gains', 'iae', 'stable', 'evaluations', 'wall_time_s', 'refine']:
    assert k in j, k
for k in ['kp', 'ki', 'kd']:
    assert k in j['gains'] and k in j['refine']['gains'], k
assert 'iae' in j['refine'] and 'verdict' in j['refine']
assert j['stable'] is True and j['iae'] < 1.9151, j['iae']
assert j['method'] == 'multi-start' and j['search']['starts'] == 16, (j['method'], j['search'])
assert j['refine']['runs'] == 2 and j['refine']['start_index'] in (0, 1), j['refine']
PY"
check "tune --trace writes a CSV whose best objective never increases" "python3 - \"$tmp/trace.csv\" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) > 10
vals = [float(r['best_objective']) for r in rows if r['best_objective'] not in ('inf',)]
assert all(b <= a for a, b in zip(vals, vals[1:]))
PY"
check "tune is quiet on stderr when not a terminal" "[ ! -s $tmp/err ]"

bad() {
  local name="$1"; shift
  "$pidlab" tune "$@" >/dev/null 2>"$tmp/bad"; local rc=$?
  check "$name exits 2 with one line" "[ $rc -eq 2 ] && [ \$(wc -l < $tmp/bad) -eq 1 ]"
  check "$name: one line under 300 characters" "only_line_ok $tmp/bad error:"
}
bad "unknown method" --plant linear --method simplex
bad "bad bounds" --plant linear --bounds 5,1
bad "bad objective" --plant linear --objective mse
bad "negative starts" --plant linear --starts -1
bad "zero design points" --plant linear --design-points 0
bad "zero refine starts" --plant linear --refine-starts 0
bad "multi-start with one evaluation" --plant linear --max-evals 1
bad "zn on 1/s^2" --plant linear --method ziegler-nichols
"$pidlab" tune --plant stepper --adaptive --json > "$tmp/adaptive.json"
check "tune --adaptive beats the paper's stepper IAE 1.9751" "python3 -c \"import json; j = json.load(open('$tmp/adaptive.json')); assert j['stable'] and j['iae'] < 1.9751, j['iae']\""
"$pidlab" tune --help >/dev/null; check "tune --help exits 0" "[ $? -eq 0 ]"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
