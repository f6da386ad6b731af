#!/usr/bin/env bash
# pidlab batch --set amigo on a few families (the whole batch is
# integration.batch), the search box a custom plant gets, and at_bounds.
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab="$1"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

"$pidlab" batch --help > "$tmp/help"
check "batch --help exits 0 and names its flags" "[ $? -eq 0 ] && grep -q -- '--families' $tmp/help && grep -q -- '--jobs' $tmp/help"
for bad in "--set foo" "--families P10" "--loop x" "--jobs -1"; do
  "$pidlab" batch $bad > "$tmp/out" 2> "$tmp/err"
  check "batch $bad exits 2 with one line naming the flag" \
    "[ $? -eq 2 ] && only_line_ok $tmp/err '${bad%% *}' && [ ! -s $tmp/out ]"
done

# P9 (a lag and a damped pair, ten plants): the JSON, the files of --out,
# and the Done-when line on them.
"$pidlab" batch --families P9 --json --out "$tmp/out_dir" > "$tmp/batch.json" 2> "$tmp/err"
check "batch --families P9 --json --out exits 0" "[ $? -eq 0 ]"
check "the JSON: 10 plants, every key, pidlab <= a feasible AMIGO, Ms <= 1.4 + 1e-3" "python3 - $tmp/batch.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j['set'] == 'amigo' and j['loop'] == 'sampled' and len(j['plants']) == 10, j.keys()
for key in ('wins', 'ties', 'losses', 'plants', 'amigo_feasible', 'pidlab_feasible'): assert key in j['summary'], key
for p in j['plants']:
    for key in ('family', 'parameter', 'value', 'tau', 'amigo', 'pidlab', 'ratio', 'box', 'model', 'dt_s', 'horizon_s'):
        assert key in p, key
    a, q = p['amigo'], p['pidlab']
    for key in ('k', 'ti_s', 'td_s', 'gains', 'ms', 'load_iae', 'feasible'): assert key in a, key
    for key in ('gains', 'ms', 'load_iae', 'feasible', 'source', 'at_bounds'): assert key in q, key
    assert q['feasible'] and q['ms'] <= 1.4 + 1e-3, p
    if a['feasible']: assert q['load_iae'] <= a['load_iae'], p
    assert abs(a['gains']['tf'] - a['td_s'] / 10) < 1e-12, a
assert j['summary']['losses'] == 0, j['summary']
PY"
check "--out writes batch.json, batch.csv (a row per plant) and batch.png" \
  "[ -s $tmp/out_dir/batch.json ] && [ \$(wc -l < $tmp/out_dir/batch.csv) -eq 11 ] && head -c 8 $tmp/out_dir/batch.png | od -c | grep -q 'P   N   G'"
"$pidlab" batch --families P9 > "$tmp/table" 2> "$tmp/err"
check "the table: a row per plant and the summary line" \
  "[ \$(grep -c '^P9 ' $tmp/table) -eq 10 ] && grep -q 'AMIGO feasible' $tmp/table && grep -q 'at_bounds' $tmp/table"

# --loop continuous: the delay-free P4 is scored on the exact continuous loop;
# a plant with dead time says why it is not (the method of steps is too slow
# for the batch's searches).
"$pidlab" batch --families P4,P6 --loop continuous --json > "$tmp/cont.json" 2> "$tmp/err"
check "batch --loop continuous scores P4 and names why P6 is not scored" "python3 - $tmp/cont.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j['loop'] == 'continuous', j['loop']
for p in j['plants']:
    if p['family'] == 'P4':
        assert p['pidlab']['feasible'] and p['pidlab']['ms'] <= 1.4 + 1e-3, p
        if p['amigo']['feasible']: assert p['pidlab']['load_iae'] <= p['amigo']['load_iae'], p
    else:
        assert not p['pidlab']['feasible'] and 'dead time' in p['message'], p
PY"

# The search box of a custom plant: (s + 1)^3 has AMIGO's FOPDT T = L = 1.5,
# kp = 0.65, so the box is [0, 6.5]; the spec echoes it and runs again to the
# same numbers; --bounds overrides it. (The box is the searching methods': a custom
# plant's default method is the design engine, which searches no box.)
"$pidlab" tune --num 1 --den 1,3,3,1 --method multi-start --max-evals 200 --json > "$tmp/box.json"
check "tune on (s + 1)^3 takes the box [0, 6.5] from the plant and echoes it" "python3 - $tmp/box.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert abs(j['box']['upper'] - 6.5) < 1e-4 and j['box']['lower'] == 0, j['box']
assert j['spec']['bounds'] == [j['box']['lower'], j['box']['upper']], j['spec']['bounds']
assert isinstance(j['at_bounds'], list)
PY"
"$pidlab" tune --spec "$tmp/box.json" --json > "$tmp/box2.json"
check "its spec runs again to the same gains and box" "python3 - $tmp/box.json $tmp/box2.json <<'PY'
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:])
assert a['gains'] == b['gains'] and a['box'] == b['box'] and a['spec'] == b['spec'], (a['gains'], b['gains'])
PY"
"$pidlab" tune --num 1 --den 1,3,3,1 --method multi-start --max-evals 200 > "$tmp/box.txt"
check "the text says where the box came from" "grep -q '^box  *\[0, 6.5' $tmp/box.txt"
"$pidlab" tune --num 1 --den 1,3,3,1 --method multi-start --max-evals 200 --bounds 0,2 --json > "$tmp/given.json"
check "--bounds overrides the plant's box" "python3 -c \"import json; j = json.load(open('$tmp/given.json')); assert j['box']['upper'] == 2, j['box']\""
"$pidlab" tune --plant linear --method multi-start --json > "$tmp/paper.json"
check "the paper's 1/s^2 keeps [0, 30]" "python3 -c \"import json; j = json.load(open('$tmp/paper.json')); assert j['box'] == {'lower': 0, 'upper': 30}, j['box']\""

# tune --robust on 1/s^2 ends on the box's edge, and says so.
"$pidlab" tune --plant linear --robust --json > "$tmp/robust.json"
check "tune --robust on 1/s^2: at_bounds names kp_hi and ki_hi" "python3 -c \"import json; j = json.load(open('$tmp/robust.json')); assert {'kp_hi', 'ki_hi'} <= set(j['at_bounds']), j['at_bounds']\""
"$pidlab" tune --plant linear --robust > "$tmp/robust.txt"
check "and the text says it too" "grep -q '^at bounds .*kp_hi, ki_hi' $tmp/robust.txt"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
