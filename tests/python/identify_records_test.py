#!/usr/bin/python3
"""cli.identify_records_RECORD: `pidlab identify` on a real record of
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


def pidlab_fit(pidlab, record, model, u0, seed):
    path = os.path.join(ref.DATA, record + ".csv")
    out = subprocess.run([pidlab, "identify", "--csv", path, "--model", model, "--u0", repr(u0), "--seed",
                          str(seed), "--json", "--quiet"], capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError("pidlab identify exited %d: %s" % (out.returncode, out.stderr.strip()))
    return json.loads(out.stdout)


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
    print("%d failures" % failures)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
