#!/usr/bin/python3
"""cli.identify_peer: `pidlab identify --json` against an independent fit in
scipy (tests/python/identify_peer.py: the exact ZOH response with a
fractional delay by scipy.linalg.expm, fitted by
scipy.optimize.least_squares from a grid of starts; no pidlab code), on the
same CSV, for P1D, P2D, P2DU and P1DI with delays off the sample grid.

  * Noise-free records simulated in Python: pidlab recovers the true
    parameters to 1e-6 relative (the two simulations are the same model).
  * Noisy records (30 dB, fixed seeds): where both converge (least_squares
    status > 0, both costs equal to 1e-8 relative), both give the same
    parameters to 1e-6 relative. Prints the largest relative difference.

Usage: identify_peer_test.py PIDLAB
"""

import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import identify_peer as peer  # noqa: E402

TOL = 1e-6
DT = 0.1
SAMPLES = 300
U0, Y0 = 0.5, 2.0
TRUTHS = {
    "p1d": [2.5, 3.1, 0.37],
    "p2d": [1.7, 4.2, 1.3, 0.63],
    "p2du": [0.8, 1.9, 0.35, 0.37],
    "p1di": [0.45, 2.2, 0.37],
}

failures = 0


def check(ok, what):
    global failures
    print(("ok   " if ok else "FAIL: ") + what)
    failures += 0 if ok else 1


def pidlab_fit(pidlab, path, model):
    out = subprocess.run([pidlab, "identify", "--csv", path, "--model", model, "--json"], capture_output=True,
                         text=True)
    if out.returncode != 0:
        raise RuntimeError("pidlab identify exited %d: %s" % (out.returncode, out.stderr.strip()))
    j = json.loads(out.stdout)
    return np.array([j["parameters"][name]["value"] for name in peer.NAMES[model]]), j


def relative(a, b):
    return float(np.max(np.abs(a - b) / np.abs(b)))


def main():
    pidlab = sys.argv[1]
    t = np.arange(SAMPLES) * DT
    with tempfile.TemporaryDirectory() as tmp:
        for i, (model, truth) in enumerate(TRUTHS.items()):
            rng = np.random.default_rng(10 + i)
            du = peer.step_rich_input(SAMPLES, rng)
            clean = peer.simulate(model, truth, du, DT)
            path = os.path.join(tmp, model + "_clean.csv")
            peer.write_csv(path, t, du + U0, clean + Y0)
            ours, _ = pidlab_fit(pidlab, path, model)
            check(relative(ours, np.array(truth)) <= TOL,
                  "%s noise-free, simulated in scipy: pidlab recovers %s, worst relative error %.2g"
                  % (model, dict(zip(peer.NAMES[model], truth)), relative(ours, np.array(truth))))

            # 30 dB; y[0] noisy too: both estimate y0 with the model.
            y = clean + rng.normal(0.0, np.std(clean) / np.sqrt(1000.0), SAMPLES) + Y0
            u = du + U0
            path = os.path.join(tmp, model + ".csv")
            peer.write_csv(path, t, u, y)
            ours, j = pidlab_fit(pidlab, path, model)
            theirs, cost, result = peer.fit(model, t, u, y)
            converged = result.status > 0 and abs(cost - j["cost"]) <= 1e-8 * j["cost"]
            check(converged, "%s noisy: both converge to the same cost (pidlab %.17g, scipy %.17g, status %d)"
                  % (model, j["cost"], cost, result.status))
            check(abs(j["y0"] - result.y0) <= TOL * abs(result.y0) and j["y0_estimated"],
                  "%s noisy: the estimated y0 agrees (pidlab %.12g, scipy %.12g)" % (model, j["y0"], result.y0))
            worst = relative(ours, theirs)
            check(worst <= TOL, "%s noisy: pidlab %s, scipy %s, worst relative difference %.2g"
                  % (model, np.array2string(ours, precision=10), np.array2string(theirs, precision=10), worst))
    print("%d failure(s)" % failures)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
