#!/usr/bin/env bash
# Tuning over the LCM trio (inside the private network namespace that
# `pidlab launch --isolated` creates) equals the local sampled tuning bit for
# bit: same gains, same IAE, same number of evaluations.
set -uo pipefail
pidlab="$1"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
args=(tune --method nelder-mead --plant linear --loop sampled --dt 1e-3 --horizon 5 --max-evals 8 --starts 1 --refine none --json)
"$pidlab" launch --isolated -- "$pidlab" "${args[@]}" --backend lcm > "$tmp/lcm.json" 2> "$tmp/lcm.err"
rc=$?
"$pidlab" "${args[@]}" --backend local > "$tmp/local.json"
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
check "tune over the trio exits 0" "[ $rc -eq 0 ]"
check "trio and local tuning agree bit for bit" "python3 - $tmp/lcm.json $tmp/local.json <<'PY'
import json, sys
a = json.load(open(sys.argv[1])); b = json.load(open(sys.argv[2]))
assert a['backend'] == 'lcm' and b['backend'] == 'local'
for k in ['gains', 'iae', 'evaluations', 'objective', 'stable']:
    assert a[k] == b[k], (k, a[k], b[k])
assert a['evaluations'] == 8 and a['stable']
print('  gains', a['gains'], 'iae', a['iae'])
PY"
[ $rc -eq 0 ] || tail -5 "$tmp/lcm.err"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
