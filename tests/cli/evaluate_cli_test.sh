#!/usr/bin/env bash
# pidlab evaluate from the command line: the 13 reference IAEs through --json,
# the JSON keys, --help, and every bad-input path (exit 2, one stderr line
# naming the value, no core dump).
# Usage: evaluate_cli_test.sh PIDLAB_BINARY PAPER_TABLES_CSV
set -euo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule

if [[ $# -ne 2 ]]; then
  echo "usage: $0 PIDLAB_BINARY PAPER_TABLES_CSV" >&2
  exit 2
fi
pidlab=$(realpath -- "$1")
csv=$(realpath -- "$2")
[[ -x $pidlab ]] || { echo "FAIL: $pidlab is not an executable" >&2; exit 1; }
[[ -r $csv ]] || { echo "FAIL: cannot read $csv" >&2; exit 1; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"  # any core file would land here
ulimit -c unlimited 2>/dev/null || true

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

# ---- --help ----
status=0
"$pidlab" evaluate --help >help.out 2>help.err || status=$?
if [[ $status -eq 0 ]] && grep -q -- "--gains" help.out; then
  pass "evaluate --help exits 0 and lists --gains"
else
  fail "evaluate --help exited $status"
fi

# ---- JSON keys ----
status=0
"$pidlab" evaluate --plant linear --gains 29.6558,0.4977,28.3216 --json >keys.json 2>keys.err || status=$?
if [[ $status -eq 0 ]] && python3 - keys.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
for k in ["plant", "gains", "loop", "iae", "rise_time_s", "overshoot_pct", "settling_time_s", "stable",
          "closed_loop_poles"]:
    assert k in j, k
for k in ["kp", "ki", "kd"]:
    assert k in j["gains"], k
assert j["plant"] == "double_integrator", j["plant"]
assert abs(j["gains"]["kp"] - 29.6558) < 1e-12 and abs(j["gains"]["kd"] - 28.3216) < 1e-12
assert j["loop"] == "continuous" and j["stable"] is True
assert len(j["closed_loop_poles"]) == 3
for p in j["closed_loop_poles"]:
    assert p["re"] < 0, p
PY
then
  pass "--json has plant, gains.kp/ki/kd, loop, iae, rise/overshoot/settling, stable, closed_loop_poles"
else
  fail "--json keys (exit $status)"
fi

# An unstable loop is reported, with null objectives and all its poles.
status=0
"$pidlab" evaluate --plant linear --gains 1,10,0 --json >unstable.json 2>/dev/null || status=$?
if [[ $status -eq 0 ]] && python3 - unstable.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["stable"] is False
assert j["iae"] is None
assert len(j["closed_loop_poles"]) == 3, j["closed_loop_poles"]
PY
then
  pass "unstable loop: stable false, iae null, three poles"
else
  fail "unstable loop report (exit $status)"
fi

# ---- The 13 reference rows ----
row=0
while IFS=, read -r table plant method amplitude kp ki kd _ _ _ _ ref_rise ref_over ref_settle ref_iae; do
  [[ $table == table ]] && continue
  row=$((row + 1))
  args=(evaluate --plant "$plant" --gains "$kp,$ki,$kd" --json)
  [[ -n $amplitude ]] && args+=(--disturbance-amplitude "$amplitude")
  status=0
  "$pidlab" "${args[@]}" >row.json 2>row.err || status=$?
  name="table $table $plant $method${amplitude:+ A=$amplitude}"
  if [[ $status -ne 0 ]]; then
    fail "$name: exit $status: $(head -c 200 row.err)"
    continue
  fi
  if msg=$(python3 - row.json "$ref_iae" "$ref_rise" "$ref_over" "$ref_settle" "$amplitude" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
ref_iae, ref_rise, ref_over, ref_settle = map(float, sys.argv[2:6])
disturbed = sys.argv[6] != ""
# ref_iae is the IAE of the response to the reference alone (y1 of eq. 17).
iae = j["iae_undisturbed"] if disturbed else j["iae"]
errors = []
if not j["stable"]:
    errors.append("not stable")
if abs(iae - ref_iae) > 1e-4 * ref_iae:
    errors.append(f"iae {iae} vs {ref_iae}")
if not disturbed and j["iae"] != j["iae_undisturbed"]:
    errors.append("iae != iae_undisturbed without disturbance")
if abs(j["rise_time_s"] - ref_rise) > 0.01 * ref_rise:
    errors.append(f"rise {j['rise_time_s']} vs {ref_rise}")
if abs(j["overshoot_pct"] - ref_over) > max(0.01 * ref_over, 0.05):
    errors.append(f"overshoot {j['overshoot_pct']} vs {ref_over}")
if abs(j["settling_time_s"] - ref_settle) > 0.01 * ref_settle:
    errors.append(f"settling {j['settling_time_s']} vs {ref_settle}")
print("; ".join(errors) if errors else f"iae {iae:.6f}")
sys.exit(1 if errors else 0)
PY
  ); then
    pass "$name: $msg"
  else
    fail "$name: $msg"
  fi
done <"$csv"
if [[ $row -eq 13 ]]; then pass "paper_tables.csv has 13 rows"; else fail "paper_tables.csv has $row rows, expected 13"; fi

# ---- Bad input: exit 2, exactly one stderr line naming the value, no core ----
bad() {
  local what=$1 needle=$2
  shift 2
  local status=0
  rm -f core core.*
  "$pidlab" "$@" >bad.out 2>bad.err || status=$?
  local lines
  lines=$(wc -l <bad.err)
  if [[ $status -ne 2 ]]; then
    fail "$what: exit $status, expected 2 (stderr: $(head -c 200 bad.err))"
  elif [[ $lines -ne 1 ]]; then
    fail "$what: $lines stderr lines, expected 1"
  elif ! why=$(only_line_ok bad.err "$needle"); then
    fail "$what: $why"
  elif ! grep -qF -- "$needle" bad.err; then
    fail "$what: stderr does not name '$needle': $(cat bad.err)"
  elif [[ -s bad.out ]]; then
    fail "$what: wrote to stdout"
  elif compgen -G 'core*' >/dev/null; then
    fail "$what: dumped core"
  else
    pass "$what: exit 2, one line naming '$needle'"
  fi
}

# A plant's dead time (docs/deadtime.md): out of range, or where it is not supported yet (the continuous
# loop with dead time is compared with a scipy reference in cli.dde_reference).
F=(--plant custom --num 1 --den 1,1 --gains 1,1,0)
bad "negative delay" "--delay -1" evaluate --loop sampled "${F[@]}" --delay -1
bad "NaN delay" "--delay 'nan'" evaluate --loop sampled "${F[@]}" --delay nan
bad "huge delay" "--delay 1e+09" evaluate --loop sampled "${F[@]}" --delay 1e9
bad "delay of more stored inputs than the analysis takes" "--delay 2 s at dt 0.001 s" evaluate --loop sampled \
  "${F[@]}" --delay 2
bad "ideal derivative, relative degree 1 and a delay on the continuous loop (neutral)" \
  "kd 0.1 with no derivative filter on a plant of relative degree 1" evaluate --loop continuous \
  --plant custom --num 1 --den 1,1 --gains 1,1,0.1 --delay 0.3
bad "delay on the nonlinear motor" "--delay 0.01 s: --plant 'stepper_nonlinear' with dead time" \
  evaluate --loop sampled --plant stepper_nonlinear --dt 1e-4 --gains 1,1,0 --delay 0.01
bad "delay with Monte Carlo" "--monte-carlo with --delay" evaluate --loop sampled "${F[@]}" --delay 0.3 \
  --monte-carlo 5
bad "tune ziegler-nichols with a delay" "ziegler-nichols with a plant dead time" tune --loop sampled \
  --plant custom --num 1 --den 1,1 --delay 0.3 --method ziegler-nichols
status=0
"$pidlab" evaluate --loop sampled "${F[@]}" --delay 0.3 --horizon 25 --sample-time 0.05 --json --samples-csv delay.csv >delay.json 2>delay.err ||
  status=$?
if [[ $status -eq 0 ]] && /usr/bin/python3 - delay.json delay.csv <<'PY'
import csv, json, sys
j = json.load(open(sys.argv[1]))
assert j["spec"]["delay"] == 0.3 and j["stable"] is True, j["spec"]
y = [float(r["y"]) for r in csv.DictReader(open(sys.argv[2]))]
assert y[6] == 0.0 and y[7] > 0.0, y[:8]  # y rests until t = L = 0.3 s (ts 0.05 s)
PY
then
  pass "a sampled loop with --delay 0.3 runs, echoes \"delay\": 0.3 and rests for the dead time"
else
  fail "a sampled loop with --delay 0.3 (exit $status: $(head -c 200 delay.err))"
fi

bad "unknown plant" "quadruple_integrator" evaluate --plant quadruple_integrator --gains 1,2,3
bad "NaN gain" "nan" evaluate --plant linear --gains nan,2,3
bad "negative gain" "-2" evaluate --plant linear --gains 1,-2,3
bad "malformed number 1,x,3" "'x'" evaluate --plant linear --gains 1,x,3
bad "two gains" "1,2" evaluate --plant linear --gains 1,2
bad "--dt 0 (continuous)" "dt 0" evaluate --plant linear --gains 1,2,3 --dt 0
bad "--dt 0 (sampled)" "dt 0" evaluate --plant linear --gains 1,2,3 --loop sampled --dt 0
bad "--dt -0.001" "-0.001" evaluate --plant linear --gains 1,2,3 --loop sampled --dt -0.001
bad "sample time 0.05 not a multiple of dt 0.03" "0.03" \
  evaluate --plant linear --gains 1,2,3 --loop sampled --sample-time 0.05 --dt 0.03
bad "--loop bogus" "bogus" evaluate --plant linear --gains 1,2,3 --loop bogus
bad "unknown flag" "--bogus" evaluate --plant linear --gains 1,2,3 --bogus
bad "malformed --dt" "abc" evaluate --plant linear --gains 1,2,3 --dt abc
bad "improper custom plant" "strictly proper" evaluate --num 1,0 --den 1,1 --gains 1,2,3
bad "--reference 0" "reference 0" evaluate --plant linear --gains 1,2,3 --reference 0
bad "--reference nan" "nan" evaluate --plant linear --gains 1,2,3 --reference nan

# ---- --reference A: iae_per_unit = iae / A, a linear loop scales with A ----
status=0
"$pidlab" evaluate --plant stepper_motor --gains 20.8836,26.607,12.4866 --json >ref1.json 2>/dev/null || status=$?
"$pidlab" evaluate --plant stepper_motor --gains 20.8836,26.607,12.4866 --reference 0.01 --json \
  >ref001.json 2>/dev/null || status=$?
if [[ $status -eq 0 ]] && python3 - ref1.json ref001.json <<'PY'
import json, sys
one, dut = (json.load(open(f)) for f in sys.argv[1:3])
assert one["reference"] == 1.0 and dut["reference"] == 0.01, (one["reference"], dut["reference"])
assert one["iae_per_unit"] == one["iae"], one
assert abs(dut["iae_per_unit"] - dut["iae"] / 0.01) <= 1e-12 * dut["iae_per_unit"], dut
assert abs(dut["iae"] - 0.01 * one["iae"]) <= 1e-12 * dut["iae"], (dut["iae"], one["iae"])
assert abs(dut["final_value"] - 0.01) <= 1e-9, dut["final_value"]
assert abs(dut["overshoot_pct"] - one["overshoot_pct"]) <= 1e-6
PY
then
  pass "--reference 0.01: reference and iae_per_unit in the JSON, IAE = 0.01 x IAE(1), same overshoot"
else
  fail "--reference 0.01 (exit $status)"
fi

# ---- pidlab linearize: eq. (3) from the nonlinear motor's autodiff Jacobian ----
status=0
"$pidlab" linearize --plant stepper_nonlinear --json >lin.json 2>lin.err || status=$?
if [[ $status -eq 0 ]] && python3 - lin.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["den"][0] == 1.0 and len(j["den"]) == 4 and len(j["num"]) == 1, j
for a, b in zip(j["den"] + j["num"], j["eq3"]["den"] + j["eq3"]["num"]):
    assert abs(a - b) <= 1e-9 * abs(b), (a, b)
PY
then
  pass "linearize --plant stepper_nonlinear --json is eq. (3), monic"
else
  fail "linearize (exit $status): $(cat lin.err)"
fi
bad "nonlinear plant on the continuous loop" "--loop sampled" evaluate --plant stepper_nonlinear --gains 1,1,1
bad "--voltage-limit on a linear plant" "stepper_nonlinear" evaluate --plant stepper_motor --gains 1,1,1 --voltage-limit 24
bad "linearize a linear plant" "stepper_motor" linearize --plant stepper_motor
status=0
"$pidlab" evaluate --plant stepper_nonlinear --loop sampled --dt 1e-4 --horizon 2 --gains 20.8836,26.607,12.4866 \
  --reference 1 --json >lost.json 2>/dev/null || status=$?
if [[ $status -eq 0 ]] && python3 - lost.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["status"] == "lost_steps" and j["motor"]["lost_steps"] is True, j.get("motor")
assert "LOST STEPS" in j["motor"]["note"]
PY
then
  pass "a 1 rad step of the paper's gains on the nonlinear motor is reported as lost steps"
else
  fail "lost steps report (exit $status)"
fi

# A dead-time plant: evaluate prints the load \int|e|dt and --samples-csv
# writes u and the load response (u_load cancels the unit load at the end;
# u(0+) = kp + kd / tf, the filtered derivative's kick; y_load's sum is the
# JSON's load_iae).
status=0
"$pidlab" evaluate --plant custom --num 1 --den 1,1 --delay 0.5 --gains 1,0.8,0.1 --derivative-filter 0.01 \
  --horizon 20 --sample-time 0.04 --samples-csv deadtime.csv >deadtime.txt 2>deadtime.err || status=$?
"$pidlab" evaluate --plant custom --num 1 --den 1,1 --delay 0.5 --gains 1,0.8,0.1 --derivative-filter 0.01 \
  --horizon 20 --sample-time 0.04 --json >deadtime.json 2>>deadtime.err || status=$?
if [[ $status -eq 0 ]] && grep -q '^load |e| dt' deadtime.txt && python3 - deadtime.csv deadtime.json <<'PY'
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1])))
j = json.load(open(sys.argv[2]))
assert list(rows[0]) == ["t", "r", "y", "e", "n", "u", "y_load", "u_load"], list(rows[0])
assert len(rows) == 501, len(rows)
u = [float(r["u"]) for r in rows]
yl = [float(r["y_load"]) for r in rows]
ul = [float(r["u_load"]) for r in rows]
assert abs(u[0] - (1 + 0.1 / 0.01)) < 1e-9, u[0]
assert abs(u[-1] - 1) < 1e-3 and abs(ul[-1] + 1) < 1e-3 and abs(yl[-1]) < 1e-3, (u[-1], ul[-1], yl[-1])
assert all(abs(y) < 1e-15 for y in yl[:12]) and abs(yl[25]) > 0.1, yl[:30]  # the load reaches y after the 0.5 s delay
s = sum(abs(y) for y in yl)
assert abs(s - j["load_iae"]) <= 1e-9 * s, (s, j["load_iae"])
assert abs(j["load_iae_continuous"] - 1 / 0.8) < 1e-3, j["load_iae_continuous"]
PY
then
  pass "evaluate on a dead-time plant prints the load |e| dt and --samples-csv writes u, y_load and u_load"
else
  fail "evaluate on a dead-time plant (exit $status): $(head -c 300 deadtime.err) $(grep load deadtime.txt)"
fi

echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
