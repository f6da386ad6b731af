#!/usr/bin/env bash
# The spec (docs/spec.md): every --json result echoes the spec it ran under
# "spec", and `--spec FILE` runs it again to the same numbers, bit for bit:
# a continuous, a sampled, a disturbed, a filtered and a tuned case (the LCM
# case is tests/integration/spec_rerun_test.sh). A flag given next to --spec
# overrides the file; a bad spec file is bad input naming the key.
# usage: spec_cli_test.sh PIDLAB
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab=$1
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
passed=0 failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

# same A.json B.json [KEY...]: the two objects equal, but for the keys named.
same() {
  local a=$1 b=$2; shift 2
  /usr/bin/python3 - "$a" "$b" "$@" <<'PY'
import json, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
for k in sys.argv[3:]:
    a.pop(k, None); b.pop(k, None)
if a != b:
    diff = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
    print("differ in", diff); sys.exit(1)
PY
}

rerun() {  # rerun NAME COMMAND ARGS...: COMMAND --json, then --spec of it, equal
  local name=$1 cmd=$2; shift 2
  if ! "$pidlab" "$cmd" "$@" --json >"$name.json" 2>"$name.err"; then fail "$name: $(cat "$name.err")"; return; fi
  if ! "$pidlab" "$cmd" --spec "$name.json" --json >"$name.again.json" 2>"$name.err"; then
    fail "$name: --spec: $(cat "$name.err")"; return
  fi
  if same "$name.json" "$name.again.json" wall_time_s; then pass "$name: --spec of its result gives the same JSON"
  else fail "$name: --spec of its result differs"; fi
  # The "spec" object alone is a spec file too.
  /usr/bin/python3 -c 'import json,sys; json.dump(json.load(open(sys.argv[1]))["spec"], open(sys.argv[2], "w"))' \
    "$name.json" "$name.spec.json"
  "$pidlab" "$cmd" --spec "$name.spec.json" --json >"$name.third.json" 2>/dev/null
  if same "$name.json" "$name.third.json" wall_time_s; then pass "$name: its bare spec gives the same JSON"
  else fail "$name: its bare spec differs"; fi
}

rerun continuous evaluate --plant oscillator --gains 2,1,1.5
rerun sampled evaluate --plant stepper --gains 20.8836,26.607,12.4866 --loop sampled --dt 1e-4 --horizon 2
rerun disturbed evaluate --plant linear --gains 29.6558,0.4977,28.3216 --disturbance-amplitude 0.2 \
  --disturbance-period 3
rerun filtered evaluate --plant stepper --gains 2.71,30,0.1535 --derivative-filter-ratio 10 --max-ms 1.6
rerun limited evaluate --num 1 --den 1,0.5,0.1 --gains 1.12,0.23,1.3 --loop sampled --output-limits -2,inf \
  --anti-windup back-calculation --derivative-on measurement
rerun noisy_chirp evaluate --loop sampled --plant custom --num 1 --den 1,2,1 --gains 0,0,0 --horizon 5 \
  --disturbance chirp --disturbance-amplitude 0.5 --chirp-band 0.1,5 --measurement-noise 0.01 --seed 3
/usr/bin/python3 - noisy_chirp.json <<'PY' && pass "noisy_chirp: the spec echoes the chirp and the measurement noise" || fail "noisy_chirp: echo"
import json, sys
j = json.load(open(sys.argv[1]))
s = j["spec"]
assert s["measurement_noise"] == 0.01 and s["chirp_band"] == [0.1, 5] and s["chirp_duration"] == 0, s
assert s["disturbance"] == "chirp" and s["seed"] == 3, s
PY
rerun delayed evaluate --loop sampled --plant custom --num 1 --den 1,1 --delay 0.3 --gains 1,1,0
/usr/bin/python3 - delayed.json <<'PY' && pass "delayed: the spec echoes \"delay\": 0.3" || fail "delayed: echo"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["spec"]["delay"] == 0.3 and j["spec"]["loop"] == "sampled", j["spec"]
assert j["stable"] is True and j["iae"] > 0, j
PY
rerun delayed_tune tune --loop sampled --dt 0.01 --plant custom --num 1 --den 1,1 --delay 0.3 --bounds 0,3 \
  --method nelder-mead --starts 1 --max-evals 60 --horizon 10
rerun montecarlo evaluate --plant stepper --gains 20.8836,26.607,12.4866 --monte-carlo 20 --spread 10%
rerun tuned tune --plant oscillator --max-evals 300 --design-points 64
rerun robust tune --plant stepper --robust --max-evals 300 --design-points 64 --max-ms 1.5

# The robust preset is resolved in the echo: what ran, not what was typed.
/usr/bin/python3 - robust.json <<'PY' && pass "robust: the echoed spec holds the preset's values" || fail "robust: echo"
import json, sys
s = json.load(open(sys.argv[1]))["spec"]
assert s["robust"] is True and s["objective"] == "setpoint-load", s
assert s["derivative_filter_ratio"] == 10 and s["max_ms"] == 1.5 and s["max_time_constant"] == 2.5, s
PY

# A flag next to --spec overrides the file.
"$pidlab" evaluate --spec continuous.json --gains 3,1,1.5 --json >override.json 2>/dev/null
"$pidlab" evaluate --plant oscillator --gains 3,1,1.5 --json >direct.json 2>/dev/null
if same override.json direct.json; then pass "a flag given with --spec overrides the file"
else fail "a flag given with --spec does not override the file"; fi

# A plant named on the command line replaces the file's, whatever form each
# was given in: a custom num/den file under --plant, a built-in under --num/--den.
# (The file's time scale, eq. (4)'s, is given, as a result's echo gives the
# one it ran.)
"$pidlab" evaluate --plant custom --num 1 --den 1,1 --gains 1,1,0 --horizon 25 --sample-time 0.05 --json >custom.json 2>/dev/null
"$pidlab" evaluate --spec custom.json --plant oscillator --json >replaced.json 2>err.txt &&
  "$pidlab" evaluate --plant oscillator --gains 1,1,0 --json >direct2.json 2>/dev/null &&
  same replaced.json direct2.json && pass "--plant replaces a spec file's custom num/den" ||
  fail "--plant over a spec file's custom plant: $(head -c 300 err.txt)"
"$pidlab" evaluate --spec continuous.json --num 1 --den 1,2,1 --json >replaced2.json 2>err.txt &&
  "$pidlab" evaluate --num 1 --den 1,2,1 --gains 2,1,1.5 --horizon 25 --sample-time 0.05 --json >direct3.json 2>/dev/null &&
  same replaced2.json direct3.json && pass "--num/--den replace a spec file's built-in plant" ||
  fail "--num/--den over a spec file's plant: $(head -c 300 err.txt)"

# docs/spec.md's example, as written there.
"$pidlab" evaluate --plant oscillator --gains 2,1,1.5 --loop sampled --json > result.json &&
  "$pidlab" evaluate --spec result.json --json > again.json &&
  "$pidlab" evaluate --spec result.json --gains 3,1,1.5 > text.out &&
  cmp -s result.json again.json && grep -q "kp = 3" text.out && grep -q "sampled" text.out &&
  pass "docs/spec.md's example runs as written" || fail "docs/spec.md's example"

# Bad spec files: exit 2, one line naming the file and the key.
bad() {  # bad NAME NEEDLE JSON
  local why=""
  printf '%s' "$3" >bad.json
  "$pidlab" evaluate --spec bad.json >/dev/null 2>bad.err
  local status=$?
  if [[ $status -eq 2 ]] && why=$(only_line_ok bad.err "$2"); then pass "bad spec $1: $(cat bad.err)"
  else fail "bad spec $1: exit $status, ${why:-}"; fi
}
bad "unknown key" "'horizn' is unknown" '{"plant": "oscillator", "gains": [1, 2, 3], "horizn": 3}'
bad "wrong type" "'horizon' must be a number" '{"plant": "oscillator", "gains": [1, 2, 3], "horizon": "long"}'
bad "not JSON" "not valid JSON" '{"plant": '
bad "another version" "version 7" '{"version": 7}'
bad "bad value" "horizon" '{"plant": "oscillator", "gains": [1, 2, 3], "horizon": 1e300}'
bad "no gains" "--gains is required" '{"plant": "oscillator"}'
"$pidlab" evaluate --spec missing.json >/dev/null 2>bad.err
if [[ $? -eq 2 ]] && why=$(only_line_ok bad.err "missing.json"); then pass "a missing spec file is bad input naming it"
else fail "missing spec file: ${why:-}"; fi
# A rule broken only when the spec is built (evaluate, tune, export): the
# line names the file as well as the value.
built() {  # built NAME NEEDLE COMMAND_AND_FLAGS... (the spec in built.json)
  local name=$1 needle=$2 why=""; shift 2
  "$pidlab" "$@" --spec built.json >/dev/null 2>bad.err
  local status=$?
  if [[ $status -eq 2 ]] && why=$(only_line_ok bad.err "--spec 'built.json': ") && grep -qF -- "$needle" bad.err
  then pass "a spec that does not build names the file ($name): $(cat bad.err)"
  else fail "a spec that does not build ($name): exit $status, ${why:-$(cat bad.err)}"; fi
}
printf '%s' '{"plant": "double_integrator", "gains": [3.9, 0.06, 4.9], "loop": "sampled", "sample_time": 0.0155, "horizon": 10}' >built.json
built "evaluate" "whole multiple of the sample time" evaluate
built "export" "whole multiple of the sample time" export --lang c --out built_export

echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
