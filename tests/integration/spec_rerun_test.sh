#!/usr/bin/env bash
# The LCM case of the spec's promise: an evaluation and a tuning over the
# process trio echo their spec, and that spec run again, in process or over
# the trio, gives the same numbers bit for bit (docs/spec.md).
# Runs in the private network namespace ctest gives it (unshare -n).
# usage: spec_rerun_test.sh BIN_DIR
set -uo pipefail
bin=$1
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
private_network_up
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
passed=0 failed=0
pass() { echo "PASS $1"; passed=$((passed + 1)); }
fail() { echo "FAIL $1"; failed=$((failed + 1)); }
same() {  # same A.json B.json [KEY...]
  local a=$1 b=$2; shift 2
  /usr/bin/python3 - "$a" "$b" "$@" <<'PY'
import json, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
for k in sys.argv[3:]:
    a.pop(k, None); b.pop(k, None)
if a != b:
    print("differ in", [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]); sys.exit(1)
PY
}
run() { "$bin/pidlab" launch --isolated -- "$bin/pidlab" "$@"; }

run evaluate --backend lcm --plant oscillator --gains 2,1,1.5 --horizon 5 --disturbance-amplitude 0.1 \
  --json >lcm.json 2>err || fail "evaluate over the trio: $(tail -1 err)"
"$bin/pidlab" evaluate --spec lcm.json --json >local.json 2>err || fail "evaluate --spec: $(tail -1 err)"
if same lcm.json local.json backend steps_per_second realtime; then
  pass "an evaluation over the trio, run again in process from its spec: the same numbers"
else fail "evaluation over the trio and its spec in process differ"; fi
run evaluate --backend lcm --spec lcm.json --json >lcm2.json 2>err || fail "--spec over the trio: $(tail -1 err)"
if same lcm.json lcm2.json steps_per_second realtime; then pass "its spec run again over the trio: the same numbers"
else fail "its spec over the trio differs"; fi

# A plant with dead time (docs/deadtime.md): the spec echoes "delay", and
# runs again bit for bit in process and over the trio.
run evaluate --backend lcm --plant custom --num 1 --den 1,1 --delay 0.3 --gains 1,1,0 --horizon 5 \
  --json >delay_lcm.json 2>err || fail "a delayed plant over the trio: $(tail -1 err)"
"$bin/pidlab" evaluate --spec delay_lcm.json --json >delay_local.json 2>err ||
  fail "evaluate --spec (delay): $(tail -1 err)"
if same delay_lcm.json delay_local.json backend steps_per_second realtime &&
  /usr/bin/python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); assert j["spec"]["delay"] == 0.3' \
    delay_local.json; then
  pass "a delayed plant over the trio, run again in process from its spec: the same numbers"
else fail "a delayed plant over the trio and its spec in process differ"; fi

# An identified model as the plant (docs/identify.md, "The identified model
# as a plant"): the episode carries its num/den/delay as a custom plant's (the
# plant process reads no file); bit for bit in process, and equal to the
# custom plant of the same num/den/delay over the trio.
cat >model.json <<'JSON'
{"model": "p1d",
 "parameters": {"Kp": {"value": 1, "standard_error": 0.01}, "Tp1": {"value": 1, "standard_error": 0.01},
                "Td": {"value": 0.3, "standard_error": 0.01}},
 "transfer_function": {"num": [1], "den": [1, 1], "delay_s": 0.3},
 "covariance": {"ok": true, "message": "", "matrix": [[1e-4, 0, 0], [0, 1e-4, 0], [0, 0, 1e-4]]}}
JSON
run evaluate --backend lcm --model model.json --gains 1,1,0 --horizon 5 \
  --json >model_lcm.json 2>err || fail "a model plant over the trio: $(tail -1 err)"
"$bin/pidlab" evaluate --spec model_lcm.json --json >model_local.json 2>err ||
  fail "evaluate --spec (model): $(tail -1 err)"
if same model_lcm.json model_local.json backend steps_per_second realtime &&
  /usr/bin/python3 -c '
import json, sys
m, d = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
assert m["spec"]["plant"] == "model:model.json", m["spec"]["plant"]
assert m["iae"] == d["iae"] and m["samples"] == d["samples"], (m["iae"], d["iae"])' model_local.json delay_lcm.json; then
  pass "a model plant over the trio: its spec in process and the custom plant of its num/den/delay give the same numbers"
else fail "a model plant over the trio differs from its spec in process or from the custom plant"; fi

# A closed-loop PRBS experiment with noise on the measured y
# (docs/identify.md): the spec echoes "measurement_noise", and runs again bit
# for bit in process.
run evaluate --backend lcm --plant double_integrator --gains 2,1,1.5 --horizon 5 --disturbance prbs \
  --disturbance-amplitude 0.2 --noise-hold 0.05 --seed 9 --measurement-noise 0.01 \
  --json >noisy_lcm.json 2>err || fail "measurement noise over the trio: $(tail -1 err)"
"$bin/pidlab" evaluate --spec noisy_lcm.json --json >noisy_local.json 2>err ||
  fail "evaluate --spec (measurement noise): $(tail -1 err)"
if same noisy_lcm.json noisy_local.json backend steps_per_second realtime &&
  /usr/bin/python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); assert j["spec"]["measurement_noise"] == 0.01' \
    noisy_local.json; then
  pass "measurement noise over the trio, run again in process from its spec: the same numbers"
else fail "measurement noise over the trio and its spec in process differ"; fi

run tune --backend lcm --loop sampled --plant linear --horizon 5 --max-evals 40 --design-points 16 --refine none \
  --json >tune_lcm.json 2>err || fail "tune over the trio: $(tail -1 err)"
"$bin/pidlab" tune --spec tune_lcm.json --json >tune_local.json 2>err || fail "tune --spec: $(tail -1 err)"
if same tune_lcm.json tune_local.json backend wall_time_s; then
  pass "a tuning over the trio, run again in process from its spec: the same tuning"
else fail "tuning over the trio and its spec in process differ"; fi

echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
