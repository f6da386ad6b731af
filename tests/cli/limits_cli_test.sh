#!/usr/bin/env bash
# The input limits and the exit-status rule of README.md ("Exit status and
# limits"): every number typed is finite and at most 1e12 in magnitude, plants
# have at most 64 coefficients, one evaluation at most 5e7 steps / 1e7 samples
# / 1e6 disturbance switches, one tuning at most 5e9 loop steps, plot and
# --trajectory-csv at most 1e7 points, --seed is a whole number, and an output
# path that cannot be written is bad input. Each case must exit 2 with exactly
# one stderr line of under 300 characters, within 1 s (under `timeout 5`, so a
# regression fails instead of hanging).
# Usage: limits_cli_test.sh PIDLAB_BINARY
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule

if [[ $# -ne 1 ]]; then
  echo "usage: $0 PIDLAB_BINARY" >&2
  exit 2
fi
pidlab=$(realpath -- "$1")
[[ -x $pidlab ]] || { echo "FAIL: $pidlab is not an executable" >&2; exit 1; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

# bad NAME NEEDLE ARGS...: exit 2, one stderr line containing NEEDLE, shorter
# than 300 characters, nothing on stdout, in under a second.
bad() {
  local what=$1 needle=$2
  shift 2
  local status=0 start end ms lines chars
  start=$(date +%s%N)
  timeout 5 "$pidlab" "$@" >bad.out 2>bad.err || status=$?
  end=$(date +%s%N)
  ms=$(((end - start) / 1000000))
  lines=$(wc -l <bad.err)
  chars=$(head -n 1 bad.err | wc -c)
  if [[ $status -eq 124 ]]; then
    fail "$what: still running after 5 s"
  elif [[ $status -ne 2 ]]; then
    fail "$what: exit $status, expected 2 (stderr: $(head -c 300 bad.err))"
  elif [[ $lines -ne 1 ]]; then
    fail "$what: $lines stderr lines, expected 1: $(head -c 300 bad.err)"
  elif [[ $chars -ge 300 ]]; then
    fail "$what: a stderr line of $chars characters: $(head -c 300 bad.err)"
  elif ! why=$(only_line_ok bad.err "$needle"); then
    fail "$what: $why"
  elif ! grep -qF -- "$needle" bad.err; then
    fail "$what: stderr does not contain '$needle': $(cat bad.err)"
  elif [[ -s bad.out ]]; then
    fail "$what: wrote to stdout"
  elif [[ $ms -ge 1000 ]]; then
    fail "$what: took $ms ms, expected under 1000"
  else
    pass "$what: exit 2 in $ms ms, one line of $chars characters"
  fi
}

# good NAME ARGS...: the value at the limit is still accepted (exit 0).
good() {
  local what=$1
  shift
  local status=0
  timeout 20 "$pidlab" "$@" >good.out 2>good.err || status=$?
  if [[ $status -eq 0 ]]; then
    pass "$what: accepted"
  else
    fail "$what: exit $status: $(head -c 300 good.err)"
  fi
}

list() {  # list N VALUE: "VALUE,VALUE,..." with N items
  local n=$1 v=$2 i out=$2
  for ((i = 1; i < n; ++i)); do out+=",$v"; done
  echo "$out"
}

# ---- Magnitudes: gains, coefficients, every number typed ----
bad "gains 1e308 (evaluate)" "1e308" evaluate --plant linear --gains 1e308,1e308,1e308
bad "gains 1e308 (plot, oscillator)" "1e308" plot --plant oscillator --gains 1e308,1e308,1e308 --out plots
bad "gains 1e308 (plot, stepper)" "1e308" plot --plant stepper --gains 1e308,1e308,1e308 --out plots
bad "gain 1e13 just above the limit" "1e13" evaluate --plant stepper --gains 1e13,0,0
bad "gain inf" "inf" evaluate --plant linear --gains 1,inf,1
bad "coefficient 1e308" "1e308" evaluate --num 1 --den 1,1e308,1 --gains 1,1,1
bad "leading coefficient 1e-300" "1e-300" evaluate --num 1 --den 1e-300,1e12,1 --gains 1,1,1
bad "stepper inertia 1e-300 (coefficients out of range)" "stepper motor" \
  evaluate --plant stepper --stepper inertia_kg_m2=1e-300 --gains 1,1,1
bad "--horizon 1e300" "1e300" evaluate --plant linear --gains 1,1,1 --horizon 1e300
bad "--horizon 1e400 (overflows a double)" "1e400" evaluate --plant linear --gains 1,1,1 --horizon 1e400
bad "--dt nan" "nan" evaluate --plant linear --gains 1,1,1 --loop sampled --dt nan
bad "--disturbance-phase 1e300" "1e300" \
  evaluate --plant stepper --gains 20.8836,26.607,12.4866 --disturbance-amplitude 1 --disturbance-phase 1e300
bad "--disturbance-amplitude inf" "inf" evaluate --plant linear --gains 1,1,1 --disturbance-amplitude inf
bad "--output-limits 1e13" "1e13" evaluate --plant linear --gains 1,1,1 --loop sampled --output-limits -1,1e13
bad "--bounds 0,1e13" "1e13" tune --plant linear --bounds 0,1e13
bad "--episode-timeout 1e308" "1e308" evaluate --plant linear --gains 1,1,1 --backend lcm --episode-timeout 1e308
bad "--drop-rate inf" "inf" launch --drop-rate inf -- true
# launch --roles: a subset of plant,controller,disturbance, each once (before anything starts).
bad "launch --roles plant,foo" "'foo' is not a role" launch --roles plant,foo -- true
bad "launch --roles ''" "--roles names no role" launch --roles '' -- true
bad "launch --roles plant,,controller" "'' is not a role" launch --roles plant,,controller -- true
bad "launch --roles plant,plant" "'plant' is named twice" launch --roles plant,plant -- true
good "gain 1e12 at the limit" evaluate --plant linear --gains 1e12,0,0
good "--output-limits -inf,5 (inf: no limit)" evaluate --plant linear --gains 1,1,1 --loop sampled --output-limits -inf,5

# ---- --seed is a whole number ----
bad "--seed -1 (evaluate)" "-1" evaluate --plant linear --gains 1,1,1 --seed -1
bad "--seed -1 (tune)" "-1" tune --plant linear --seed -1
bad "--seed -1 (report)" "-1" report --seed -1 --quick --no-figures --out report
bad "--seed 2^64" "18446744073709551616" evaluate --plant linear --gains 1,1,1 --seed 18446744073709551616
bad "--seed 1.5" "1.5" evaluate --plant linear --gains 1,1,1 --seed 1.5
good "--seed 2^64-1" evaluate --plant linear --gains 29.6558,0.4977,28.3216 --seed 18446744073709551615

# ---- Work: steps, samples, coefficients, disturbance switches, tuning ----
bad "sampled --dt 1e-7 (2.5e8 steps)" "5e7" evaluate --plant stepper --gains 20.8836,26.607,12.4866 --loop sampled --dt 1e-7
bad "tune sampled --dt 2e-8" "5e7" tune --plant linear --loop sampled --dt 2e-8
bad "--sample-time 1e-7 (2.5e8 samples)" "1e7" evaluate --plant linear --gains 1,1,1 --sample-time 1e-7
bad "square disturbance period 1e-6 (5e7 switches)" "1e6" \
  evaluate --plant stepper --gains 20.8836,26.607,12.4866 --disturbance-amplitude 1 --disturbance-period 1e-6
bad "noise hold 1e-9" "1e6" \
  evaluate --plant linear --gains 1,1,1 --disturbance noise --disturbance-amplitude 1 --noise-hold 1e-9
bad "prbs clock 1e-9" "1e6" \
  evaluate --plant linear --gains 1,1,1 --disturbance prbs --disturbance-amplitude 1 --noise-hold 1e-9
bad "prbs clock 0" "prbs clock (noise hold) 0 s must be positive" \
  evaluate --plant linear --gains 1,1,1 --disturbance prbs --disturbance-amplitude 1 --noise-hold 0
chirp() { echo evaluate --plant linear --gains 1,1,1 --loop sampled --disturbance chirp --disturbance-amplitude 1; }
bad "chirp band F1 at the Nyquist frequency" "--chirp-band 0,500 Hz: F1 must be below the Nyquist frequency" \
  $(chirp) --chirp-band 0,500
bad "chirp band F1 above Nyquist at a coarser dt" "--chirp-band 1,60 Hz" $(chirp) --chirp-band 1,60 --dt 0.01
bad "chirp band F0 >= F1" "--chirp-band 5,5 Hz must have 0 <= F0 < F1" $(chirp) --chirp-band 5,5
bad "chirp band negative F0" "--chirp-band -1,5 Hz must have 0 <= F0 < F1" $(chirp) --chirp-band -1,5
bad "chirp band not given" "--chirp-band 0,0 Hz must have 0 <= F0 < F1" $(chirp)
bad "chirp band nan" "--chirp-band" $(chirp) --chirp-band nan,5
bad "chirp band 1e13" "--chirp-band" $(chirp) --chirp-band 0,1e13
bad "chirp duration negative" "--chirp-duration -1 s must be >= 0" $(chirp) --chirp-band 0,5 --chirp-duration -1
bad "chirp on the continuous loop" "--disturbance 'chirp': the continuous loop cannot integrate a chirp exactly" \
  evaluate --plant linear --gains 1,1,1 --disturbance chirp --disturbance-amplitude 1 --chirp-band 0,5
bad "measurement noise negative" "--measurement-noise -0.1 must be >= 0" \
  evaluate --plant linear --gains 1,1,1 --loop sampled --measurement-noise -0.1
bad "measurement noise inf" "--measurement-noise" \
  evaluate --plant linear --gains 1,1,1 --loop sampled --measurement-noise inf
bad "measurement noise 1e13" "--measurement-noise" \
  evaluate --plant linear --gains 1,1,1 --loop sampled --measurement-noise 1e13
bad "measurement noise on the continuous loop" "--measurement-noise 0.01: noise on the measured y needs --loop sampled" \
  evaluate --plant linear --gains 1,1,1 --measurement-noise 0.01
bad "measurement noise in tune" "--measurement-noise 0.01: tune does not take measurement noise" \
  tune --plant linear --loop sampled --measurement-noise 0.01
bad "tune sampled --dt 1e-5 (5000 x 2.5e6 steps)" "5e9" tune --plant stepper --loop sampled --dt 1e-5 \
  --method multi-start
bad "tune --max-evals 1e8 (1e8 x 501 samples)" "5e9" tune --plant linear --max-evals 100000000
bad "tune square period 1e-3 (5000 x 5e4 switches)" "5e9" \
  tune --plant stepper --method multi-start --disturbance-amplitude 1 --disturbance-period 1e-3
bad "plot of 2.5e7 points" "more than 1e7 points" \
  plot --plant stepper --gains 20.8836,26.607,12.4866 --loop sampled --dt 1e-6 --horizon 25 --out plots
bad "--trajectory-csv of 2.5e7 rows" "more than 1e7" \
  evaluate --plant stepper --gains 20.8836,26.607,12.4866 --loop sampled --dt 1e-6 --trajectory-csv t.csv
bad "20,000-coefficient --den" "more than 64" evaluate --num 1 --den "$(list 20000 1)" --gains 1,1,1
bad "65-coefficient --den" "more than 64" evaluate --num 1 --den "$(list 65 1)" --gains 1,1,1
bad "65-coefficient --num" "more than 64" evaluate --num "$(list 65 1)" --den 1,1 --gains 1,1,1
good "64-coefficient --den" evaluate --num 1 --den "$(list 64 1)" --gains 1,1,1
good "tune sampled --dt 1e-5 with --max-evals 20" \
  tune --plant stepper --loop sampled --dt 1e-5 --max-evals 20 --refine none

# ---- Echoes are truncated and on one line ----
bad "65,000-gain list" "must be three numbers" evaluate --plant linear --gains "$(list 65000 1)"
bad "1,000-character plant name" "unknown plant" evaluate --plant "$(printf 'x%.0s' {1..1000})" --gains 1,1,1
bad "a newline in the plant name" "unknown plant 'a\\nb'" evaluate --plant $'a\nb' --gains 1,1,1
bad "a newline in a CLI11-parsed number" "--horizon" evaluate --plant linear --gains 1,1,1 --horizon $'1\n2'
bad "a 5,000-character unexpected argument" "not expected" \
  evaluate --plant linear --gains 1,1,1 "$(printf 'y%.0s' {1..5000})"
bad "a 5,000-character --loop" "--loop" evaluate --plant linear --gains 1,1,1 --loop "$(printf 'z%.0s' {1..5000})"

# ---- An output path that cannot be written is bad input (exit 2) ----
mkdir -p folder
bad "evaluate --samples-csv in a missing folder" "--samples-csv" \
  evaluate --plant linear --gains 1,1,1 --samples-csv missing/samples.csv
bad "evaluate --trajectory-csv in a missing folder" "--trajectory-csv" \
  evaluate --plant linear --gains 1,1,1 --loop sampled --trajectory-csv missing/trajectory.csv
bad "evaluate --samples-csv naming a folder" "--samples-csv" \
  evaluate --plant linear --gains 1,1,1 --samples-csv folder
bad "tune --trace in a missing folder (before the search)" "--trace" \
  tune --plant linear --trace missing/trace.csv
bad "report --out that cannot be created" "--out" report --quick --no-figures --out /proc/pidlab-report
bad "plot --out that cannot be created" "--out" \
  plot --plant linear --gains 29.6558,0.4977,28.3216 --out /proc/pidlab-plots
bad "launch --log in a missing folder (before starting anything)" "--log" launch --log missing/trio.lcm -- true
[[ -e missing ]] && fail "a missing output folder was created" || pass "no missing output folder was created"

echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
