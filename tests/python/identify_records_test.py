#!/usr/bin/python3
"""study.identify_records_RECORD: `pidlab identify` on a real record of
tests/data/identify (README.md there names the sources) against the reference
fits of tests/python/identify_reference.py (scipy, many starts, a delay
profile; no pidlab code), stored in tests/data/identify/reference_fits.json.

For every case of the record (model, u0) and every seed 0, 1, 2:
  * pidlab's cost is within 1e-5 relative of the reference's, or lower;
  * the cost pidlab reports is the cost of the parameters and y0 it reports,
    recomputed by the reference's own simulator, to 1e-9 relative;
  * P2D's cost is never above P1D's by more than 1e-4 relative;
  * a parameter the reference finds at a bound (Td at 0, Zeta at 1) gets a
    warning naming it, and no standard error (a one-sided interval).
For P1D and P2D, seed 0, in every mode (the default; u0 estimated; the
initial condition estimated, and at steady state; FOH between samples):
  * the JSON names the mode, and the cost pidlab reports is the cost of the
    parameters, u0, y0 and initial state (its initial_free_response) it
    reports, re-simulated by identify_reference.response_piecewise, to 1e-9
    relative; the worst relative difference per mode is printed;
  * a record whose u is constant (the step test) is refused u0 estimated,
    in one line.
The stored reference is re-checked on a sample: its parameters re-simulate
to its cost, and a local fit from them finds nothing lower (1e-9 relative).

Usage: identify_records_test.py PIDLAB RECORD
"""

import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import identify_reference as ref  # noqa: E402

SEEDS = (0, 1, 2)
failures = 0


def check(ok, what):
    global failures
    print(("ok   " if ok else "FAIL: ") + what, flush=True)
    failures += 0 if ok else 1


def run_identify(pidlab, record, model, flags):
    path = os.path.join(ref.DATA, record + ".csv")
    return subprocess.run([pidlab, "identify", "--csv", path, "--model", model] + flags + ["--json", "--quiet"],
                          capture_output=True, text=True)


def pidlab_fit(pidlab, record, model, u0, seed, flags=()):
    out = run_identify(pidlab, record, model, ["--u0", u0 if isinstance(u0, str) else repr(u0), "--seed",
                                               str(seed)] + list(flags))
    if out.returncode != 0:
        raise RuntimeError("pidlab identify exited %d: %s" % (out.returncode, out.stderr.strip()))
    return json.loads(out.stdout)


# The modes re-simulated by identify_reference.response_piecewise (its own
# realisation, exact piece by piece, any grid): name, the flags after --u0,
# whether u0 is estimated, and what the simulator is given.
#   before: the input before the record ("u0" or "u[0]");
#   state: "zero", "steady" (at rest under u[0], computed here: Kp (u[0] - u0)
#   and zero derivatives) or "reported" (the JSON's initial_free_response).
MODES = [
    ("the default (u0 given, zero initial state, ZOH)", [], False, "zoh", "u0", "zero"),
    ("u0 estimated", [], True, "zoh", "u0", "zero"),
    ("the initial condition estimated", ["--initial-condition", "estimate"], False, "zoh", "u[0]", "reported"),
    ("the initial condition at steady state", ["--initial-condition", "steady-state"], False, "zoh", "u[0]",
     "steady"),
    ("FOH between samples", ["--intersample", "foh"], False, "foh", "u0", "zero"),
]


def relative(a, b):
    return abs(a - b) / abs(b)


def main():
    pidlab, record = sys.argv[1], sys.argv[2]
    with open(ref.REFERENCE) as f:
        stored = [c for c in json.load(f)["fits"] if c["record"] == record]
    check(len(stored) > 0, "%s: the reference holds %d fits" % (record, len(stored)))
    t, u, y = ref.load(record)
    dt = (t[-1] - t[0]) / (len(t) - 1)
    # The reference, re-checked on a sample: its first case.
    c = stored[0]
    values = [c["parameters"][n] for n in ref.NAMES[c["model"]]]
    again = ref.cost_of(record, c["model"], c["u0"], values, c["y0"])
    check(relative(again, c["cost"]) <= 1e-9, "%s %s: the reference's parameters re-simulate to its cost "
          "(%.12g against %.12g)" % (record, c["model"], again, c["cost"]))
    q = np.log(values[1:-1]) if c["model"] != "p2du" else [np.log(values[1]), values[2]]
    _, local = ref.solve(c["model"], np.append(q, values[-1]), t, u - c["u0"], y - y[0])
    check(local >= c["cost"] * (1 - 1e-9), "%s %s: a local fit from the reference finds no lower cost (%.12g)"
          % (record, c["model"], local))
    p1d = {}
    for c in stored:
        model, u0 = c["model"], c["u0"]
        for seed in SEEDS:
            j = pidlab_fit(pidlab, record, model, u0, seed)
            what = "%s %s --u0 %g --seed %d" % (record, model, u0, seed)
            check(j["cost"] <= c["cost"] * (1 + 1e-5),
                  "%s: cost %.10g, the reference's %.10g (relative %+.2g; %d of %d starts at the best)"
                  % (what, j["cost"], c["cost"], (j["cost"] - c["cost"]) / c["cost"], j["starts_at_best"],
                     j["starts"]))
            values = [j["parameters"][n]["value"] for n in ref.NAMES[model]]
            again = ref.cost_of(record, model, u0, values, j["y0"])
            check(relative(again, j["cost"]) <= 1e-9, "%s: the reported cost re-simulates (%.12g against %.12g)"
                  % (what, again, j["cost"]))
            if model == "p1d":
                p1d[seed] = j["cost"]
            if model == "p2d" and seed in p1d:
                check(j["cost"] <= p1d[seed] * (1 + 1e-4), "%s: P2D's cost %.10g is not above P1D's %.10g"
                      % (what, j["cost"], p1d[seed]))
            bounds = {"Td": c["parameters"]["Td"] <= 1e-6 * dt}
            if model == "p2du":
                bounds["Zeta"] = c["parameters"]["Zeta"] >= 1 - 1e-6
            for name, at in bounds.items():
                if not at:
                    continue
                warned = any(w.startswith(name + " = ") and "bound" in w for w in j["warnings"])
                check(warned and j["parameters"][name]["standard_error"] is None
                      and "at_bound" in j["parameters"][name],
                      "%s: %s at its bound is warned of, with no standard error" % (what, name))
    # Every mode, one seed, P1D and P2D: the cost pidlab reports is the cost
    # of what it reports (parameters, u0, y0, the initial state), re-simulated
    # by a simulator that is not pidlab's.
    _, u, _ = ref.load(record)
    worst = {}
    for c in [c for c in stored if c["model"] in ("p1d", "p2d")]:
        model = c["model"]
        for name, flags, u0_estimated, hold, before, state in MODES:
            what = "%s %s, %s" % (record, model, name)
            if u0_estimated and np.all(u == u[0]):
                # A step record: Kp and u0 enter only as Kp (u - u0).
                out = run_identify(pidlab, record, model, ["--u0", "estimate"])
                check(out.returncode == 2 and "constant input" in out.stderr
                      and len(out.stderr.strip().splitlines()) == 1,
                      "%s: a record whose input is constant is refused in one line (exit %d)"
                      % (what, out.returncode))
                continue
            j = pidlab_fit(pidlab, record, model, "estimate" if u0_estimated else c["u0"], 0, flags)
            check(j["u0_estimated"] == u0_estimated and j["intersample"] == hold
                  and (u0_estimated or j["u0"] == c["u0"]),
                  "%s: the JSON says the mode it fitted (u0 %.10g, %s, initial condition %s)"
                  % (what, j["u0"], j["intersample"], j["initial_condition"]))
            values = [j["parameters"][n]["value"] for n in ref.NAMES[model]]
            u0 = j["u0"]
            free = None
            if state == "reported":
                free = j["initial_free_response"]
            elif state == "steady":
                free = [values[0] * (u[0] - u0)] + [0.0] * (len(ref.NAMES[model]) - 3)
            else:
                check(not any(j["initial_free_response"]), "%s: the initial state reported is zero" % what)
            again = ref.cost_of_mode(record, model, values, u0, j["y0"], hold, u[0] if before == "u[0]" else u0,
                                     free)
            rel = relative(again, j["cost"])
            worst[name] = max(worst.get(name, 0.0), rel)
            check(rel <= 1e-9, "%s: the reported cost %.12g re-simulates independently to %.12g (relative %.1e)"
                  % (what, j["cost"], again, rel))
    for name, rel in worst.items():
        print("worst relative difference, %s: %.1e" % (name, rel))
    print("%d failures" % failures)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
