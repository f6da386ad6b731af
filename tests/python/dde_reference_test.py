#!/usr/bin/python3
"""cli.dde_reference: `pidlab evaluate --json` on the continuous loop with dead
time against tests/python/dde_reference.py (scipy's DOP853 by the method of
steps, no code shared), on FOPDT, SOPDT, integrating and 3-lag plants with PI,
filtered and ideal PID, with and without a square disturbance, L from 0.05 to
2 s. Asserts iae, itae, load_iae and y at every sample to 1e-6 relative (y
relative to the largest |y| of its response) and prints the worst errors.
Also: an ideal derivative on a plant of relative degree 1 with a dead time
exits 2 with one line; L -> 0+ approaches the undelayed loop's IAE; the
sampled loop's IAE approaches the continuous delayed one as dt -> 0 (O(dt)).

Usage: dde_reference_test.py PIDLAB
"""

import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import dde_reference  # noqa: E402  (tests/python/dde_reference.py, beside this file)
TOL = 1e-6
HORIZON = "10"

# (name, num, den, delay, gains, derivative filter tf, square amplitude)
CASES = [
    ("fopdt_pi", "1", "1,1", 0.3, "0.5,0.5,0", 0.0, 0.0),
    ("fopdt_pi_amigo", "1", "1,1", 1.0, "0.25,0.25,0", 0.0, 0.0),
    ("fopdt_pi_square", "1", "1,1", 0.5, "0.6,0.6,0", 0.0, 0.5),
    ("fopdt_pid_filtered", "1", "1,1", 0.2, "1,1,0.2", 0.05, 0.0),
    ("fopdt_pi_long", "1", "1,1", 2.0, "0.2,0.15,0", 0.0, 0.0),
    ("fopdt_pi_short_square", "1", "1,1", 0.05, "2,2,0", 0.0, 0.3),
    ("sopdt_pi", "1", "1,2,1", 0.5, "0.5,0.3,0", 0.0, 0.0),
    ("sopdt_pid_ideal", "1", "1,2,1", 0.5, "1,0.5,0.4", 0.0, 0.0),
    ("sopdt_pid_ideal_square", "1", "1,2,1", 0.3, "1,0.6,0.5", 0.0, 0.5),
    ("sopdt_pid_filtered_square", "1", "1,2,1", 1.0, "0.5,0.25,0.3", 0.03, 0.5),
    ("sopdt_pid_ideal_short", "1", "1,2,1", 0.05, "3,2,1", 0.0, 0.0),
    ("sopdt_lags_pid_filtered", "1", "1,2.5,1", 0.7, "0.8,0.3,0.5", 0.05, 0.0),
    ("integrating_pi", "1", "1,1,0", 0.5, "0.3,0.02,0", 0.0, 0.0),
    ("integrating_pid_ideal", "1", "1,1,0", 0.2, "0.5,0.05,0.3", 0.0, 0.0),
    ("integrating_pid_filtered_square", "1", "1,1,0", 1.0, "0.3,0.01,0.3", 0.1, 0.2),
    ("integrating_p", "1", "1,1,0", 1.0, "0.4,0,0", 0.0, 0.0),
    ("lag3_pi", "1", "1,3,3,1", 0.5, "0.5,0.3,0", 0.0, 0.0),
    ("lag3_pid_ideal", "1", "1,3,3,1", 0.5, "1,0.5,0.8", 0.0, 0.0),
    ("lag3_pid_filtered_square", "1", "1,3,3,1", 2.0, "0.3,0.15,0.3", 0.05, 0.5),
    ("lag3_pi_short_square", "1", "1,3,3,1", 0.05, "1,0.5,0", 0.0, 0.5),
    ("lag3_pid_ideal_square", "1", "1,3,3,1", 1.0, "0.5,0.25,0.5", 0.0, 0.3),
    ("fopdt_gain2_pi", "2", "3,1", 0.8, "0.6,0.25,0", 0.0, 0.0),
]


def pidlab_args(num, den, delay, gains, tf, amp):
    args = ["evaluate", "--plant", "custom", "--num", num, "--den", den, "--delay", repr(delay), "--gains", gains,
            "--horizon", HORIZON, "--json"]
    if tf > 0.0:
        args += ["--derivative-filter", repr(tf)]
    if amp > 0.0:
        args += ["--disturbance", "square", "--disturbance-amplitude", repr(amp), "--disturbance-period", "2"]
    return args


def run_pidlab(pidlab, args, csv_path=None):
    if csv_path:
        args = args + ["--samples-csv", csv_path]
    p = subprocess.run([pidlab] + args, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit("FAIL: pidlab " + " ".join(args) + ": " + p.stderr.strip())
    return json.loads(p.stdout)


def run_reference(num, den, delay, gains, tf, amp):
    # In this interpreter (scipy imported once, not once per case): the same
    # arguments and the same object as `dde_reference.py ARGS` prints.
    args = ["--num", num, "--den", den, "--delay", repr(delay), "--gains", gains, "--tf", repr(tf),
            "--horizon", HORIZON]
    if amp > 0.0:
        args += ["--square", "%r,2" % amp]
    return dde_reference.reference(args)


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def compare_cases(pidlab, tmp):
    worst = {"iae": 0.0, "itae": 0.0, "load_iae": 0.0, "y": 0.0}
    failures = []
    for name, num, den, delay, gains, tf, amp in CASES:
        path = os.path.join(tmp, name + ".csv")
        got = run_pidlab(pidlab, pidlab_args(num, den, delay, gains, tf, amp), path)
        if not got["stable"]:
            failures.append("%s: not stable" % name)
            continue
        with open(path) as f:
            y = [float(row["y"]) for row in csv.DictReader(f)]
        ref = run_reference(num, den, delay, gains, tf, amp)
        errs = {k: rel(got[k], ref[k]) for k in ("iae", "itae", "load_iae")}
        scale = max(abs(v) for v in ref["y"])
        errs["y"] = max(abs(a - b) for a, b in zip(y, ref["y"])) / scale if len(y) == len(ref["y"]) else 1.0
        for k, v in errs.items():
            worst[k] = max(worst[k], v)
            if not v <= TOL:
                failures.append("%s: %s relative error %.3g > %g" % (name, k, v, TOL))
        print("%-34s iae %.3e  itae %.3e  load_iae %.3e  y %.3e" % (name, errs["iae"], errs["itae"],
                                                                       errs["load_iae"], errs["y"]))
    print("worst relative error over %d cases: iae %.3g, itae %.3g, load_iae %.3g, y %.3g" %
          (len(CASES), worst["iae"], worst["itae"], worst["load_iae"], worst["y"]))
    return failures


def check_neutral(pidlab):
    p = subprocess.run([pidlab, "evaluate", "--plant", "custom", "--num", "1", "--den", "1,1", "--delay", "0.3",
                        "--gains", "1,1,0.1"], capture_output=True, text=True)
    lines = p.stderr.strip().splitlines()
    if p.returncode != 2 or len(lines) != 1 or "derivative filter" not in lines[0] or "kd" not in lines[0]:
        return ["neutral loop: exit %d, stderr %r" % (p.returncode, p.stderr)]
    print("neutral loop refused:", lines[0])
    return []


def check_continuity(pidlab):
    base = ["--num", "1", "--den", "1,2,1", "--gains", "1,0.5,0.4", "--horizon", HORIZON]
    undelayed = run_pidlab(pidlab, ["evaluate", "--plant", "custom", "--json"] + base)["iae"]
    failures = []
    previous = None
    for delay in (1e-2, 1e-3, 1e-4):
        iae = run_pidlab(pidlab, ["evaluate", "--plant", "custom", "--delay", repr(delay), "--json"] + base)["iae"]
        gap = abs(iae - undelayed)
        print("L = %g: IAE %.12g, undelayed %.12g, gap %.3g" % (delay, iae, undelayed, gap))
        if previous is not None and not gap < 0.2 * previous:
            failures.append("L -> 0+: the gap %.3g at L = %g does not shrink from %.3g" % (gap, delay, previous))
        previous = gap
    if not previous < 1e-3 * undelayed:
        failures.append("L = 1e-4: IAE differs from the undelayed loop's by %.3g" % previous)
    return failures


def check_sampled_converges(pidlab):
    base = ["evaluate", "--plant", "custom", "--num", "1", "--den", "1,1", "--delay", "0.3", "--gains",
            "0.5,0.5,0", "--horizon", HORIZON, "--json"]
    continuous = run_pidlab(pidlab, base)["iae"]
    gaps = []
    for dt in ("0.002", "0.001", "0.0005"):
        sampled = run_pidlab(pidlab, base + ["--loop", "sampled", "--dt", dt])["iae"]
        gaps.append(abs(sampled - continuous))
        print("sampled dt = %s: IAE %.10g, continuous %.10g, gap %.3g" % (dt, sampled, continuous, gaps[-1]))
    ratios = [gaps[i] / gaps[i + 1] for i in range(len(gaps) - 1)]
    if not all(1.6 < r < 2.4 for r in ratios):
        return ["sampled loop -> continuous: gap ratios %s, not about 2 (O(dt))" % ratios]
    return []


def check_documented_example(pidlab):
    # docs/deadtime.md, "In every loop": the continuous loop with dead time.
    got = run_pidlab(pidlab, ["evaluate", "--plant", "custom", "--num", "1", "--den", "1,1", "--delay", "0.3",
                              "--gains", "1,1,0", "--json"])
    if not (got["stable"] and got["spec"]["delay"] == 0.3 and got["iae"] > 0):
        return ["documented example: %r" % {k: got[k] for k in ("stable", "iae")}]
    print("documented example: IAE %.12g" % got["iae"])
    return []


def main():
    pidlab = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        failures = compare_cases(pidlab, tmp)
    failures += check_documented_example(pidlab) + check_neutral(pidlab) + check_continuity(pidlab) + check_sampled_converges(pidlab)
    for f in failures:
        print("FAIL: " + f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
