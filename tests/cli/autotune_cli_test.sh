#!/usr/bin/env bash
# pidlab autotune's front door (docs/autotune.md): --help names its flags, and
# bad input is exit 2 with one line naming the value, before any trio is
# needed; --log on a file that is no log, or a log without a relay episode.
# usage: autotune_cli_test.sh PIDLAB
set -uo pipefail
pidlab=$(realpath -- "$1")
. "$(dirname "${BASH_SOURCE[0]}")/stderr_shape.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
passed=0 failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

help=$("$pidlab" autotune --help) || fail "--help exits non-zero"
missing=()
for flag in --backend --relay-amplitude --relay-bias --hysteresis --hold --u0 --y-limit --settled-cycles \
  --tolerance --timeout-periods --max-restarts --relay-time --max-time --method --robustness --max-ms \
  --max-overshoot --log --episode --json --gains --output-limits; do
  [[ $help == *"$flag"* ]] || missing+=("$flag")
done
((${#missing[@]} == 0)) && pass "--help names every flag" || fail "--help misses ${missing[*]}"

bad() {  # bad WHAT NEEDLE ARGS...
  local what=$1 needle=$2 said
  shift 2
  if said=$(bad_input_ok "$needle" "$pidlab" autotune "$@"); then pass "$what: $said"; else fail "$what: $said"; fi
}
bad "a negative relay amplitude" "-1" --num 1 --den 1,1 --relay-amplitude -1
bad "a bias as large as the amplitude" "bias 2" --num 1 --den 1,1 --relay-amplitude 1 --relay-bias 2
bad "a bias that is no number" "abc" --num 1 --den 1,1 --relay-bias abc
bad "a negative hysteresis" "-1" --num 1 --den 1,1 --hysteresis -1
bad "an unknown design method" "pso" --num 1 --den 1,1 --method pso
bad "another backend" "local" --num 1 --den 1,1 --backend local
bad "one settled cycle" "settled cycles 1" --num 1 --den 1,1 --settled-cycles 1
bad "a tolerance of 2" "tolerance 2" --num 1 --den 1,1 --tolerance 2
bad "a negative hold" "hold -1" --num 1 --den 1,1 --hold -1
bad "a longest window below the first" "window 1 s" --num 1 --den 1,1 --max-time 1
bad "an Ms bound of 1" "1" --num 1 --den 1,1 --max-ms 1
bad "previous gains that differ in sign" "-1" --num 1 --den 1,1 --gains -1,1,0
bad "an unknown scalar" "q7" --num 1 --den 1,1 --scalar q7
bad "the relay in float" "float" --num 1 --den 1,1 --scalar float
bad "fixed point without an input range" "--input-range" --num 1 --den 1,1 --output-limits -2,2 --scalar q31
bad "fixed point without output limits" "output limits" --num 1 --den 1,1 --scalar q15 --input-range -2,2
bad "an input range in double" "--input-range" --num 1 --den 1,1 --input-range -2,2
bad "verify gains of two values" "--verify-gains 1,2" --num 1 --den 1,1 --verify-gains 1,2
bad "verify gains that differ in sign" "-1" --num 1 --den 1,1 --verify-gains 1,-1,0
bad "verify gains with a negative filter" "-0.1" --num 1 --den 1,1 --verify-gains 1,1,0.1,-0.1
bad "--log of a missing file" "nothing.lcmlog" --log nothing.lcmlog
printf 'not a log' >empty.lcmlog
bad "--log of a file that is no log" "empty.lcmlog" --log empty.lcmlog

echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
