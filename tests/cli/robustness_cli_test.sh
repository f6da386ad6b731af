#!/usr/bin/env bash
# pidlab evaluate's `robustness` object against an independent computation:
# numpy evaluates C(jw) G(jw) on 400,001 log-spaced frequencies from 1e-5 to
# 1e7 rad/s (G of the stepper rebuilt from Table I by eq. (3) in Python),
# refines every maximum with scipy's bounded scalar search and every crossover
# with brentq, for the paper's Nelder-Mead gains of the three plants (ideal
# PID, and with --derivative-filter 0.01 (stepper: 1e-5) for a finite noise
# gain). Every figure
# must agree within 0.5 %. Also: the JSON keys, the notes of an infinite
# margin and of the ideal derivative, --monte-carlo, and bad input.
# Usage: robustness_cli_test.sh PIDLAB_BINARY PAPER_TABLES_CSV
set -euo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
if [[ $# -ne 2 ]]; then
  echo "usage: $0 PIDLAB_BINARY PAPER_TABLES_CSV" >&2
  exit 2
fi
pidlab=$(realpath -- "$1")
csv=$(realpath -- "$2")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

# ---- The paper's NM gains against numpy/scipy ----
cases=()
for plant in double_integrator oscillator stepper_motor; do
  gains=$(awk -F, -v p="$plant" '$2 == p && $3 == "nelder_mead" { print $5 "," $6 "," $7; exit }' "$csv")
  filtered=0.01
  [[ $plant == stepper_motor ]] && filtered=1e-5  # its loop is fast: 0.01 s destabilises it
  cases+=("$plant $gains 0" "$plant $gains $filtered")
done
# A stable stepper loop with three gain crossovers, at +91.2, -91.3 and +19.3 deg (found by
# tests/loop_delay_test.cc's seeded search): its phase margin is 19.3 deg, the smallest distance.
cases+=("stepper_motor 0.02312248198680401,0.082003684650619205,7.4018005317821451 0.00054138902437990356")
for case in "${cases[@]}"; do
  read -r plant gains tf <<<"$case"
  {
    name="$plant gains $gains tf $tf"
    if "$pidlab" evaluate --plant "$plant" --gains "$gains" --derivative-filter "$tf" --json >out.json 2>err.txt &&
      /usr/bin/python3 - out.json "$plant" "$gains" "$tf" <<'PY'
import json, math, sys
import numpy as np
from scipy.optimize import brentq, minimize_scalar

j = json.load(open(sys.argv[1]))
plant, (kp, ki, kd), tf = sys.argv[2], map(float, sys.argv[3].split(",")), float(sys.argv[4])
if plant == "double_integrator":
    num, den = [1.0], [1.0, 0.0, 0.0]
elif plant == "oscillator":
    num, den = [1.0], [1.0, 0.0, 1.0]
else:  # eq. (3) with Table I, independently of pidlab
    r, L, M, J, Nr, D, lam, Io, flux = 33.0, 5.4e-3, 0.4e-3, 0.16e-4, 6.0, 1.35e-5, math.pi / 12, 0.15, 1.2e-3
    Lp, half = L - M, Nr * lam / 2
    wnp2 = 2 * Nr**2 * flux * Io * math.cos(half) / J
    kpm = flux * math.sin(half) ** 2 / (Lp * Io * math.cos(half))
    num = [r / L * wnp2]
    den = [1.0, r / Lp + D / J, r / Lp * D / J + wnp2 * (1 + kpm), r / Lp * wnp2]

def parts(w):
    s = 1j * np.asarray(w, dtype=float)
    c = kp + ki / s + kd * s / (tf * s + 1)
    l = c * np.polyval(num, s) / np.polyval(den, s)
    return c, l

def mags(w):
    c, l = parts(w)
    return {"ms": np.abs(1 / (1 + l)), "mt": np.abs(l / (1 + l)), "noise_gain": np.abs(c / (1 + l))}

w = np.logspace(-5, 7, 400_001)
with np.errstate(all="ignore"):
    grid = mags(w)
    c, l = parts(w)
ref = {}
for key, v in grid.items():
    v = np.where(np.isfinite(v), v, -np.inf)
    i = int(np.argmax(v))
    lo, hi = w[max(i - 2, 0)], w[min(i + 2, len(w) - 1)]
    res = minimize_scalar(lambda x: -mags([math.exp(x)])[key][0], bounds=(math.log(lo), math.log(hi)),
                          method="bounded", options={"xatol": 1e-12})
    ref[key] = max(v[i], -res.fun)
# Gain crossovers |L| = 1 and phase crossovers Im L = 0 with Re L < 0.
g = np.log(np.abs(l))
pms, dms, gms = [], [], []
for k in np.nonzero(np.diff(np.sign(g)) != 0)[0]:
    if not (np.isfinite(g[k]) and np.isfinite(g[k + 1])):
        continue
    wc = brentq(lambda x: math.log(abs(parts([x])[1][0])), w[k], w[k + 1], xtol=1e-14, rtol=1e-14)
    pm = math.degrees(np.angle(parts([wc])[1][0])) + 180.0
    pm = pm - 360.0 if pm > 180.0 else pm
    pms.append(pm)
    dms.append(math.radians(pm if pm > 0 else pm + 360.0) / wc)
im = np.imag(l)
for k in np.nonzero(np.diff(np.sign(im)) != 0)[0]:
    if not (np.isfinite(im[k]) and np.isfinite(im[k + 1])) or abs(l[k]) > 1e12 or abs(l[k + 1]) > 1e12:
        continue
    wp = brentq(lambda x: np.imag(parts([x])[1][0]), w[k], w[k + 1], xtol=1e-14, rtol=1e-14)
    lp = parts([wp])[1][0]
    if lp.real < 0 and abs(lp) < 1e9:  # not the phase jump at a pole on the axis
        gms.append(1.0 / abs(lp))
# The phase margin a user reads: the smallest |arg L + 180| over the crossovers
# (MATLAB's margin); every crossover's signed margin in phase_margins_deg (allmargin).
ref["phase_margin_deg"] = min(abs(p) for p in pms) if pms else None
ref["delay_margin_s"] = min(dms) if dms else None
ref["gain_margin"] = min(gms, key=lambda x: abs(math.log(x))) if gms else None
if tf == 0 and kd > 0:
    ref["noise_gain"] = None  # unbounded: pidlab must say null
rob = j["robustness"]
bad = []
for key, want in ref.items():
    got = rob[key]
    if want is None or got is None:
        if want is not got:
            bad.append(f"{key}: pidlab {got} numpy {want}")
        continue
    err = abs(got - want) / abs(want)
    print(f"  {key:18s} pidlab {got:.6g}  numpy/scipy {want:.6g}  rel diff {err:.1e}")
    if err > 5e-3:
        bad.append(f"{key}: pidlab {got} numpy {want} ({err:.2%})")
got_pms = rob["phase_margins_deg"]
if len(got_pms) != len(pms) or any(abs(a - b) > 5e-3 * max(1.0, abs(b)) for a, b in zip(got_pms, pms)):
    bad.append(f"phase_margins_deg: pidlab {got_pms} numpy {pms}")
if bad:
    print("\n".join(bad))
    sys.exit(1)
PY
    then
      pass "$name: ms, mt, margins, delay margin, noise gain within 0.5 % of numpy/scipy"
    else
      fail "$name: $(tail -3 err.txt 2>/dev/null)"
    fi
  }
done

# ---- Keys, notes, bounds reported ----
"$pidlab" evaluate --plant double_integrator --gains 0.2999,0,30 --max-time-constant 10 --json >keys.json
if /usr/bin/python3 - keys.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
r = j["robustness"]
for k in ["ms", "mt", "gain_margin", "phase_margin_deg", "delay_margin_s", "noise_gain", "slowest_time_constant_s"]:
    assert k in r, k
assert r["noise_gain"] is None and r["notes"]["noise_gain"] == "ideal derivative: unbounded", r
assert r["gain_margin"] is None and "infinite gain margin" in r["notes"]["gain_margin"], r
assert len(r["cancellations"]) == 1 and 99 < r["slowest_time_constant_s"] < 101, r
assert any(v.startswith("time constant") for v in r["violations"]), r["violations"]
assert j["gains"]["tf"] == 0
PY
then pass "robustness keys, null with notes, the cancellation and a violated bound"; else fail "robustness keys"; fi

# ---- Several gain crossovers: --min-phase-margin reads the smallest distance to -180 deg ----
several=(--plant stepper_motor --gains 0.02312248198680401,0.082003684650619205,7.4018005317821451
  --derivative-filter 0.00054138902437990356 --json)
"$pidlab" evaluate "${several[@]}" --min-phase-margin 15 >pm15.json
"$pidlab" evaluate "${several[@]}" --min-phase-margin 25 >pm25.json
if /usr/bin/python3 - pm15.json pm25.json <<'PY'
import json, sys
r15, r25 = (json.load(open(f))["robustness"] for f in sys.argv[1:3])
assert r15["stable"] and len(r15["phase_margins_deg"]) == 3, r15
assert min(r15["phase_margins_deg"]) < 0 < r15["phase_margin_deg"], r15
assert abs(r15["phase_margin_deg"] - min(abs(m) for m in r15["phase_margins_deg"])) < 1e-12, r15
assert not any(v.startswith("phase margin") for v in r15["violations"]), r15["violations"]
assert any(v.startswith("phase margin") for v in r25["violations"]), r25["violations"]
PY
then pass "three crossovers (one at -91 deg): phase margin 19.3 deg meets 15, breaks 25"; else fail "several crossovers"; fi

"$pidlab" evaluate --plant double_integrator --gains 30,1,30 --derivative-filter-ratio 10 --json >ratio.json
if /usr/bin/python3 -c "import json,sys; g=json.load(open('ratio.json'))['gains']; assert abs(g['tf']-0.1)<1e-15, g"; then
  pass "--derivative-filter-ratio 10 gives tf = kd/(10 kp) in the gains"
else fail "--derivative-filter-ratio"; fi

# ---- Monte Carlo ----
"$pidlab" evaluate --plant double_integrator --gains 1,0.95,1 --monte-carlo 100 --spread 20% --seed 3 --json >mc1.json
"$pidlab" evaluate --plant double_integrator --gains 1,0.95,1 --monte-carlo 100 --spread 0.2 --seed 3 --json >mc2.json
if /usr/bin/python3 - mc1.json mc2.json <<'PY'
import json, sys
a, b = (json.load(open(f))["monte_carlo"] for f in sys.argv[1:])
assert a == b, "20% and 0.2 with the same seed give the same draws"
assert 0.45 < a["stable_fraction"] < 0.8, a  # 0.625 expected (Routh: b > 0.95)
for k in ["iae", "overshoot_pct", "ms"]:
    d = a[k]
    assert d["min"] <= d["median"] <= d["p95"] <= d["max"], d
PY
then pass "--monte-carlo: 20% = 0.2, seeded, stable fraction across the Routh boundary"; else fail "--monte-carlo"; fi
if "$pidlab" evaluate --plant stepper --gains 20.8836,26.607,12.4866 --monte-carlo 20 | grep -q "Table I parameters"; then
  pass "--monte-carlo on the stepper perturbs Table I parameters"
else fail "stepper Monte Carlo table"; fi

# ---- tune --robust: every bound of the preset met, finite noise gain ----
for plant in double_integrator oscillator stepper_motor; do
  "$pidlab" tune --plant "$plant" --robust --json >robust.json
  if /usr/bin/python3 - robust.json <<'PY'
import json, math, sys
j = json.load(open(sys.argv[1]))
r, c = j["robustness"], j["constraints"]
assert j["objective_kind"] == "setpoint-load" and j["load_weight"] == 1, j
assert c["max_ms"] == 1.6 and c["max_time_constant_s"] == 2.5 and c["derivative_filter_ratio"] == 10, c
g = j["gains"]
assert g["tf"] > 0 and abs(g["tf"] - g["kd"] / (10 * g["kp"])) <= 1e-9 * g["tf"], g
assert r["ms"] <= 1.6 * (1 + 1e-6) and r["slowest_time_constant_s"] <= 2.5, r
assert r["noise_gain"] is not None and math.isfinite(r["noise_gain"]), r
assert r["violations"] == [], r
assert abs(j["objective"] - (j["iae"] + j["load_iae"])) <= 1e-9 * j["objective"], j
PY
  then pass "tune --robust on $plant meets Ms <= 1.6 and tau <= 2.5 s with a finite noise gain"
  else fail "tune --robust on $plant"; fi
done
"$pidlab" tune --plant double_integrator --robust --max-ms 1.4 --objective load-iae --json >robust14.json
if /usr/bin/python3 -c '
import json, sys
j = json.load(open("robust14.json"))
assert j["constraints"]["max_ms"] == 1.4 and j["objective_kind"] == "load-iae", j
assert j["robustness"]["ms"] <= 1.4 * (1 + 1e-6), j["robustness"]'; then
  pass "flags given next to --robust override its parts"
else fail "--robust overrides"; fi
"$pidlab" tune --plant double_integrator --robust --robust-samples 6 --robust-spread 20% --max-evals 2000 \
  --json >rset.json
if /usr/bin/python3 -c '
import json
j = json.load(open("rset.json"))
s = j["robust_set"]
assert s["samples"] == 6 and s["size"] == 7 and s["spread"] == 0.2 and s["quantile"] == 1, s
assert j["objective"] >= s["nominal_objective"], j
assert j["refine"]["ran"] is False and "robust set" in j["refine"]["message"], j["refine"]'; then
  pass "--robust-samples: the worst case over nominal + 6 draws, never below the nominal objective"
else fail "--robust-samples"; fi

# ---- Bad input: exit 2, one line naming the value ----
for args in "--monte-carlo 10 --spread 150%" "--monte-carlo 10 --spread abc" "--monte-carlo -1" \
  "--max-ms 0.5" "--min-gain-margin 0.5" "--derivative-filter -1" \
  "--derivative-filter 0.1 --derivative-filter-ratio 10"; do
  status=0
  # shellcheck disable=SC2086
  "$pidlab" evaluate --plant linear --gains 1,1,1 $args >bad.out 2>bad.err || status=$?
  if [[ $status -eq 2 ]] && only_line_ok bad.err "error:"; then pass "bad input $args: exit 2, $(cat bad.err)"; else
    fail "bad input $args: exit $status, $(cat bad.err)"; fi
done

for args in "--robust-quantile 0" "--robust-quantile 1.5" "--robust-spread 100%" "--robust-samples -2" \
  "--robust-spread x"; do
  status=0
  # shellcheck disable=SC2086
  "$pidlab" tune --plant linear $args >bad.out 2>bad.err || status=$?
  if [[ $status -eq 2 ]] && only_line_ok bad.err "error:"; then pass "bad input tune $args: exit 2, $(cat bad.err)"; else
    fail "bad input tune $args: exit $status, $(cat bad.err)"; fi
done

status=0
"$pidlab" tune --plant stepper_nonlinear --robust --loop sampled --dt 1e-4 >bad.out 2>bad.err || status=$?
if [[ $status -eq 2 ]] && only_line_ok bad.err "error:" && grep -q "needs a linear plant" bad.err; then
  pass "tune --robust on the nonlinear motor: exit 2, $(cat bad.err)"
else fail "tune --robust on the nonlinear motor: exit $status, $(cat bad.err)"; fi

echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
