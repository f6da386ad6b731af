#!/usr/bin/python3
"""cli.design_reference: `pidlab tune --method optimal` against an independent
optimum (tests/python/design_reference.py: the load response by a numerical
inverse Laplace transform, the peaks on a frequency grid, SLSQP from several
starts; no code shared with pidlab), on a representative subset of Astrom and
Hagglund's AMIGO test batch (P1-P9, unit gain) and four more plants (a DC
motor, a two-tank process, 1/(s+1)^3 and a reverse-acting FOPDT).

For each plant: Ms = Mt <= 1.59 (`--robustness 1.59`), and two noise-gain
bounds: G1 = the bound pidlab's design uses by default (`design.noise_gain_bound`
of the same command without --max-noise-gain: 10 x the plant's ultimate gain,
or where it has none the noise gain that default design reached)
and G2 = 10 x G1 (where the noise bound mostly gives way to N <= 50 and
Td <= the dominant time constant). The PID of the engine on every plant, and
its PI (`--rule pi`, G1 then pidlab's PI default) on ten (PI_PLANTS).
For each case, with the reference's code:

  * pidlab's gains meet every bound (Ms, Mt, noise gain, Td, 2 <= N <= 50)
    within 0.2 % and give a stable loop;
  * their load IAE agrees with pidlab's design.load_iae within 0.5 %;
  * pidlab's IAE (recomputed by the reference, so both IAEs are measured the
    same way) is at most 1.03 x the reference optimum's under the same bounds.

The reference's own IAEs must be converged (within 1e-4 on a window twice
as long and on 4x the samples). A reverse-acting plant (a negative gain) must get gains all <= 0 and
design.reverse_acting: the reference then designs for -G, and pidlab's
gains, their sign turned, are checked against it (the same loop). One line per case
(plant, G, pidlab's design.load_iae, the reference optimum's IAE, pidlab's
gains' IAE by the reference, their ratio to the optimum's, both Ms, and
pidlab's wall time for the design, s: bench/design_bench.sh tabulates them), failing
ones starting "FAIL: ", and last `N passed, M failed`; exit 1 on any
failure. Deterministic (no random starts); about 100 s of CPU.

Usage: design_reference_test.py PIDLAB
"""

import json
import math
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import design_reference as ref  # noqa: E402  (beside this file)

MS = 1.59
G2_FACTOR = 10.0
BOUND_TOL = 2e-3  # pidlab's gains meet the bounds within 0.2 %
IAE_AGREE = 5e-3  # its load_iae and the reference's within 0.5 %
RATIO_MAX = 1.03  # within 3 % of the reference optimum
# Also designed as PIs (`--rule pi`, the engine's PI: kd = 0), both bounds.
PI_PLANTS = ("P1 T=1", "P1 T=100", "P2 T=10", "P4 n=4", "P5 a=0.1", "P6 L1=0.3", "P8 a=0.5", "motor", "tank",
             "lag3", "reverse")


def poly(*factors):
    p = np.array([1.0])
    for f in factors:
        p = np.polymul(p, np.asarray(f, float))
    return p


def fmt(v):
    return "%.17g" % v


def plants():
    """(name, num, den, delay), unit gain but for the motor, tank and reverse."""
    out = []
    for T in (0.1, 0.5, 1.0, 2.0, 6.0, 20.0, 100.0):
        out.append(("P1 T=%g" % T, [1.0], [T, 1.0], 1.0))
    for T in (0.1, 0.5, 1.0, 2.0, 10.0, 50.0):
        out.append(("P2 T=%g" % T, [1.0], poly([T, 1.0], [T, 1.0]), 1.0))
    for T in (0.02, 0.1, 0.5, 2.0, 10.0):
        out.append(("P3 T=%g" % T, [1.0], poly([1.0, 1.0], [T, 1.0], [T, 1.0]), 0.0))
    for n in (4, 5, 6, 8):
        out.append(("P4 n=%d" % n, [1.0], poly(*([[1.0, 1.0]] * n)), 0.0))
    for a in (0.1, 0.2, 0.5):
        out.append(("P5 a=%g" % a, [1.0], poly([1.0, 1.0], [a, 1.0], [a * a, 1.0], [a ** 3, 1.0]), 0.0))
    for l1 in (0.1, 0.3, 0.5, 0.9):
        out.append(("P6 L1=%g" % l1, [1.0], [1.0 - l1, 1.0, 0.0], l1))
    for T, l1 in ((1.0, 0.1), (2.0, 0.5), (5.0, 0.3), (10.0, 0.9)):
        out.append(("P7 T=%g L1=%g" % (T, l1), [T], poly([T, 1.0], [1.0 - l1, 1.0]), l1))
    for a in (0.2, 0.5, 1.0):
        out.append(("P8 a=%g" % a, [-a, 1.0], poly([1.0, 1.0], [1.0, 1.0], [1.0, 1.0]), 0.0))
    for T in (0.2, 1.0, 5.0):
        out.append(("P9 T=%g" % T, [1.0], poly([1.0, 1.0], [T * T, 1.4 * T, 1.0]), 0.0))
    out.append(("motor", [4.0], [0.351, 1.0], 0.0296))
    out.append(("tank", [0.8], [1200.0, 130.0, 1.0], 150.0))
    out.append(("lag3", [1.0], [1.0, 3.0, 3.0, 1.0], 0.0))
    out.append(("reverse", [-2.0], [5.0, 1.0], 1.0))
    return out


def run_pidlab(pidlab, num, den, delay, noise=None, pi=False):
    """(exit code, JSON or None, stderr)."""
    args = [pidlab, "tune", "--num", ",".join(fmt(v) for v in num), "--den", ",".join(fmt(v) for v in den),
            "--delay", fmt(delay), "--method", "optimal", "--robustness", fmt(MS), "--json"]
    if pi:
        args += ["--rule", "pi"]
    if noise is not None:
        args += ["--max-noise-gain", fmt(noise)]
    p = subprocess.run(args, capture_output=True, text=True)
    out = json.loads(p.stdout) if p.returncode == 0 and p.stdout.strip() else None
    return p.returncode, out, p.stderr.strip()


def check_case(pidlab, name, plant, num, den, delay, g, pi, previous):
    """One case at noise bound g: (verdict line, passed, the reference
    optimum's x or None, the IAE ratio pidlab / reference or NaN)."""
    label = name + (" PI" if pi else "")
    code, j, err = run_pidlab(pidlab, num, den, delay, g, pi)
    if code != 0 or j is None:
        return "FAIL: %-18s %10.4g pidlab exit %d: %s" % (label, g, code, err), False, None, math.nan
    problems = []
    gains = {k: float(j["gains"][k]) for k in ("kp", "ki", "kd", "tf")}
    if plant.static_gain() < 0:
        # Reverse acting: the loop of -G under -C is the loop of G under C.
        if not (j["design"].get("reverse_acting") and all(gains[k] <= 0 for k in ("kp", "ki", "kd"))):
            problems.append("a reverse-acting plant with gains %s, reverse_acting %s"
                            % (gains, j["design"].get("reverse_acting")))
        for k in ("kp", "ki", "kd"):
            gains[k] = -gains[k]
        plant = ref.Plant([-v for v in num], den, delay)
    prob = ref.Problem(plant, MS, noise=g, pi=pi)
    if pi and gains["kd"] != 0.0:
        problems.append("a PI with kd %g" % gains["kd"])
    a = prob.analyse(gains)
    for k, v in sorted(prob.violations(a).items()):
        if v > BOUND_TOL:
            problems.append("%s over its bound by %.3g %%" % (k, 100 * v))
    td_pidlab = j["design"].get("td_bound_s")
    if not pi and td_pidlab and abs(td_pidlab / prob.td_max - 1.0) > 1e-3:
        problems.append("Td bound %.6g s, the reference's %.6g s" % (td_pidlab, prob.td_max))
    iae_p = float(j["design"]["load_iae"])
    iae_pr = a["iae"]
    if max(a["iae_info"].get("change_longer", 1), a["iae_info"].get("change_finer", 1)) > 1e-4:
        problems.append("the reference's IAE of pidlab's gains not converged: %s" % a["iae_info"])
    if not abs(iae_pr / iae_p - 1.0) <= IAE_AGREE:
        problems.append("load IAE %.6g, the reference's of the same gains %.6g" % (iae_p, iae_pr))
    opt = prob.optimise(extra_starts=previous)
    x_ref, iae_r, ms_r, ratio = None, math.nan, math.nan, math.nan
    if opt is None:
        problems.append("the reference found no design meeting the bounds")
    else:
        iae_r, ms_r = opt["iae"], opt["analysis"]["ms"]
        info = opt["analysis"]["iae_info"]
        if max(info.get("change_longer", 1), info.get("change_finer", 1)) > 1e-4:
            problems.append("the reference optimum's IAE not converged: %s" % info)
        x_ref = ref.x_of(opt["gains"], pi)
        ratio = iae_pr / iae_r
        if not ratio <= RATIO_MAX:
            og, oa = opt["gains"], opt["analysis"]
            problems.append(
                "the reference is %.2f %% better: pidlab kp %.10g ki %.10g kd %.10g tf %.10g (Ms %.5g Mt %.5g "
                "noise %.5g); reference kp %.10g ki %.10g kd %.10g tf %.10g (Ms %.5g Mt %.5g noise %.5g)"
                % (100 * (ratio - 1), gains["kp"], gains["ki"], gains["kd"], gains["tf"], a["ms"], a["mt"],
                   a["noise_gain"], og["kp"], og["ki"], og["kd"], og["tf"], oa["ms"], oa["mt"], oa["noise_gain"]))
    line = "%-18s %10.4g %12.6g %12.6g %12.6g %8.4f %7.4f %7.4f %7.3f" % (
        label, g, iae_p, iae_r, iae_pr, ratio, a["ms"], ms_r, float(j.get("wall_time_s", math.nan)))
    if problems:
        return "FAIL: " + line + "  " + "; ".join(problems), False, x_ref, ratio
    return line + "  ok", True, x_ref, ratio


def main(argv):
    if len(argv) != 2:
        print(__doc__)
        return 2
    pidlab = argv[1]
    t0 = time.time()
    passed = failed = 0
    ratios = []
    print("%-18s %10s %12s %12s %12s %8s %7s %7s %7s  %s" % ("plant", "G", "pidlab IAE", "ref IAE", "pidlab(ref)",
                                                           "ratio", "Ms", "ref Ms", "time", "verdict"))
    cases = [(name, num, den, delay, False) for name, num, den, delay in plants()]
    cases += [(name, num, den, delay, True) for name, num, den, delay in plants() if name in PI_PLANTS]
    for name, num, den, delay, pi in cases:
        plant = ref.Plant(num, den, delay)
        code, base, err = run_pidlab(pidlab, num, den, delay, None, pi)
        if code != 0 or base is None:
            failed += 1
            print("FAIL: %-18s the default design: exit %d: %s" % (name, code, err))
            continue
        # No default bound (a plant whose phase never passes -180 deg, so no
        # ultimate gain): the noise gain its default design reached.
        g1 = base["design"]["noise_gain_bound"]
        if g1 is None:
            g1 = base["robustness"]["noise_gain"]
        previous = []
        for g in (g1, G2_FACTOR * g1):
            line, ok, x_ref, ratio = check_case(pidlab, name, plant, num, den, delay, g, pi, previous)
            previous = [x_ref] if x_ref is not None else []
            if ok:
                passed += 1
            else:
                failed += 1
            if np.isfinite(ratio):
                ratios.append(ratio)
            print(line)
            sys.stdout.flush()
    if ratios:
        print("ratio pidlab / reference: min %.4f, median %.4f, max %.4f over %d cases; %.1f s"
              % (min(ratios), float(np.median(ratios)), max(ratios), len(ratios), time.time() - t0))
    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
