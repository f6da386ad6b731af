#!/usr/bin/env bash
# pidlab report, end to end: the full report (trio included), every figure it
# links exists and is a PNG, bad input exits 2 naming the path. Its duration
# is measured by bench/report_bench.sh, not asserted here.
# usage: report_cli_test.sh PIDLAB PAPER_TABLES
set -u
source "$(dirname -- "$0")/../cli/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab=$1
tables=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$pidlab" report --out "$out/r" --paper-tables "$tables" --seed 1 > "$out/stdout" 2> "$out/stderr" \
  || { cat "$out/stderr"; fail "pidlab report exited $?"; }
echo "pidlab report: $(cat "$out/stdout")"

md="$out/r/report.md"
[[ -s $md ]] || fail "no report.md"
for t in II III IV V VI; do grep -q "^### Table $t:" "$md" || fail "Table $t missing"; done
grep -q "Trio run:" "$md" || fail "the LCM trio section did not run: $(grep -A1 'trio run was not' "$md")"
grep -q "bit for bit" "$md" || fail "trio result differs from the in-process sampled loop"

figures=$(grep -o '](fig[^)]*\.png)' "$md" | sed 's/^](//; s/)$//')
count=$(echo "$figures" | grep -c png)
(( count == 12 )) || fail "expected 12 figures linked, found $count"
# "Identifying the motor": eq. (3)'s DC gain and pole pair within the fit's intervals, Ms <= 1.6.
grep -q "^## Identifying the motor" "$md" || fail "section Identifying the motor missing"
grep -q "^| DC gain | .* | yes |" "$md" || fail "the identified DC gain is not within its interval of eq. (3)'s"
grep -q "^| pole pair | .* | yes |" "$md" || fail "the identified pole pair is not within its interval of eq. (3)'s"
grep -q "keep Ms ≤ 1.6 on eq. (3) and on the motor: yes" "$md" || fail "a gain set of the identify section breaks Ms <= 1.6"
grep -q "fig_motor_identified.png" "$md" || fail "the identification figure is not linked"
# "The motor itself": its tables hold numbers (IAE/A of the motor and of eq. (3), peaks) for every move.
grep -q "^## The motor itself" "$md" || fail "section The motor itself missing"
for row in "| 0.001 | none |" "| 0.01 | none |" "(one tooth pitch) | none |" "| 1 | none |" \
           "| 0.001 | 24 V |" "| 0.01 | 24 V |" "(one tooth pitch) | 24 V |" "| 1 | 24 V |"; do
  n=$(grep -F "$row" "$md" | grep -cE '\| [0-9.e+-]+ \| [0-9.e+-]+ \| [0-9.e+-]+ \|')
  (( n == 4 )) || fail "motor row '$row': $n of 4 gain sets with numbers"
done
grep -q "fig_motor_itself.png" "$md" || fail "the motor figure is not linked"
grep -q "^### pidlab's robust preset: kp, ki, kd = .*, Tf " "$md" || fail "the motor section lacks the --robust set"
# "Robust tuning": per plant, the three gain sets with numbers in every column, and one figure.
grep -q "^## Robust tuning" "$md" || fail "section Robust tuning missing"
robust=$(sed -n '/^## Robust tuning/,/^## Figures/p' "$md")
num='[0-9.e+-]+'
for set in "paper Nelder-Mead" "pidlab, paper objective" "pidlab --robust"; do
  n=$(echo "$robust" | grep -F "| $set | " |
      grep -cE "\| $num \| $num \| $num \| $num \| ($num|inf) \| ($num deg|inf) \| ($num|unbounded) \| $num % \|$")
  (( n == 3 )) || fail "robust rows '$set': $n of 3 plants with numbers"
done
(( $(echo "$robust" | grep -F "| pidlab --robust | " | grep -c unbounded) == 0 )) \
  || fail "the --robust preset has an unbounded noise gain"
for p in double_integrator oscillator stepper_motor; do
  grep -q "](fig_robust_$p.png)" "$md" || fail "robust figure of $p not linked"
done
for f in $figures; do
  [[ -s "$out/r/$f" ]] || fail "figure $f listed but missing"
  sig=$(head -c 8 "$out/r/$f" | od -An -tx1 | tr -d ' \n')
  [[ $sig == 89504e470d0a1a0a ]] || fail "$f is not a PNG (signature $sig)"
done

"$pidlab" report --out "$out/bad" --paper-tables /nonexistent/paper_tables.csv > /dev/null 2> "$out/err"
status=$?
(( status == 2 )) || fail "missing tables: exit $status, expected 2"
grep -q "/nonexistent/paper_tables.csv" "$out/err" || fail "error does not name the path: $(cat "$out/err")"
why=$(only_line_ok "$out/err" "error:") || fail "missing tables: $why"
echo PASS
