#!/usr/bin/env bash
# The whole AMIGO test batch (pidlab batch --set amigo): on every plant where
# AMIGO's own Ms <= 1.4, pidlab's load IAE is no larger, and pidlab's Ms <=
# 1.4 (+ 1e-3) by the full analysis on every plant (issue 23's Done-when line).
set -uo pipefail
pidlab="$1"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# The command of docs/deadtime.md, "The AMIGO test batch": the table on
# stdout, the JSON, CSV and figure in the folder.
"$pidlab" batch --set amigo --out "$tmp/batch" > "$tmp/table" || { echo "FAIL: pidlab batch exited $?"; exit 1; }
for f in batch.json batch.csv batch.png; do [ -s "$tmp/batch/$f" ] || { echo "FAIL: --out wrote no $f"; exit 1; }; done
[ "$(grep -c '^P[1-9] ' "$tmp/table")" -eq 133 ] || { echo "FAIL: the table has no row per plant"; exit 1; }
python3 - "$tmp/batch/batch.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
bad = []
for p in j['plants']:
    a, q = p['amigo'], p['pidlab']
    name = p['family'] + ' ' + p['label']
    if not q['feasible'] or q['ms'] > 1.4 + 1e-3: bad.append(name + ': pidlab Ms %s' % q['ms'])
    elif a['feasible'] and q['load_iae'] > a['load_iae']: bad.append(name + ': loses to AMIGO')
s = j['summary']
print('%d plants in %.1f s, AMIGO feasible on %d, pidlab wins %d, ties %d, loses %d' %
      (s['plants'], j['wall_time_s'], s['amigo_feasible'], s['wins'], s['ties'], s['losses']))
assert s['plants'] == 133, s
for b in bad: print('FAIL: ' + b)
print('PASS: the Done-when line holds on every plant' if not bad else 'FAIL: %d plants' % len(bad))
sys.exit(1 if bad else 0)
PY
