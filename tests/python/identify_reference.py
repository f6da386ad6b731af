"""Reference fits of the real records in tests/data/identify by a fitter that
shares no code with pidlab: numpy and scipy only.

The model: y_k = y0 + yhat_k, yhat the response of Kp e^(-Td s) / den(s) to
u - u0 held over each sample, from a zero state with the input at u0 before
the record (pidlab identify's default mode, with u0 given and y0 estimated).
The cost is 1/2 sum (y_k - y0 - yhat_k)^2, pidlab's.

Two simulators, neither pidlab's:
  * a uniform record with any input: identify_peer.simulate (expm of the
    augmented matrix, the held input split at the delay's fraction, the
    recursion as linear filters);
  * a step record (u - u0 the same nonzero value at every sample) on any
    grid, uniform or not: the closed-form step response of the model,
    Kp (u - u0) s(t_k - t_0 - Td).

A third, for every mode of `pidlab identify` (identify_records_test.py):
response_piecewise, any grid, the input held or linear between samples
(zoh, foh), any input before the record and any initial state (given by its
free response C A^i x, i < n), integrated exactly piece by piece between the
delayed input's breakpoints by expm of [[A, B, 0], [0, 0, 1], [0, 0, 0]].

The fit: variable projection. Kp and y0 enter linearly and are solved by
least squares for every value of the nonlinear parameters (the time
constants as logarithms, Zeta, Td), which scipy.optimize.least_squares (trf,
3-point differences, tolerances 1e-15) fits from a grid of many starts; the
best is then polished by a profile of the delay (Td held on a grid of
quarter samples around it, the rest refitted) and one last free fit. The
bounds are pidlab's: time constants in [dt/1000, 1000 T], Zeta in
[1e-3, 1 - 1e-9], Td in [0, T/2], T the record's length.

  /usr/bin/python3 tests/python/identify_reference.py            # refit all, rewrite the JSON
  /usr/bin/python3 tests/python/identify_reference.py heating    # refit one record's cases
  /usr/bin/python3 tests/python/identify_reference.py heating p1d  # one case, print only

Writes tests/data/identify/reference_fits.json (read by
identify_records_test.py). Slow (minutes): the test re-checks a sample.
"""

import json
import os
import sys

import numpy as np
from scipy import linalg, optimize

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import identify_peer as peer  # noqa: E402

DATA = os.path.join(HERE, "..", "data", "identify")
REFERENCE = os.path.join(DATA, "reference_fits.json")

# (record, model, u0): the fits the test set holds. u0 as `pidlab identify
# --u0` gives it; y0 estimated (the default).
CASES = [
    ("dryer", "p1d", 6.41),
    ("dryer", "p2d", 6.41),
    ("dryer", "p2du", 6.41),
    ("heating", "p1d", 6.0),
    ("heating", "p2d", 6.0),
    ("heating", "p2du", 6.0),
    ("tclab_step", "p1d", 0.0),
    ("tclab_step", "p2d", 0.0),
]

NAMES = {"p1d": ("Kp", "Tp1", "Td"), "p2d": ("Kp", "Tp1", "Tp2", "Td"), "p2du": ("Kp", "Tw", "Zeta", "Td")}
MIN_ZETA, MAX_ZETA = 1e-3, 1.0 - 1e-9


def load(record):
    """t, u, y of tests/data/identify/RECORD.csv."""
    d = np.genfromtxt(os.path.join(DATA, record + ".csv"), delimiter=",", names=True)
    return d["t"], d["u"], d["y"]


def uniform(t):
    h = np.diff(t)
    return bool(np.all(np.abs(h - h.mean()) <= 1e-6 * h.mean()))


def step_response(model, p, tau):
    """The unit step response of 1 / den(s) (p in NAMES order, Kp unused) at
    the times tau (0 where tau <= 0), in closed form."""
    tau = np.maximum(tau, 0.0)
    if model == "p1d":
        return -np.expm1(-tau / p[1])
    if model == "p2d":
        t1, t2 = p[1], p[2]
        if abs(t1 - t2) <= 1e-7 * max(t1, t2):
            t = 0.5 * (t1 + t2)
            return 1.0 - (1.0 + tau / t) * np.exp(-tau / t)
        return 1.0 - (t1 * np.exp(-tau / t1) - t2 * np.exp(-tau / t2)) / (t1 - t2)
    if model == "p2du":
        tw, z = p[1], p[2]
        root = np.sqrt((1.0 - z) * (1.0 + z))
        wd = root / tw
        return 1.0 - np.exp(-z * tau / tw) * (np.cos(wd * tau) + z * tau / tw * np.sinc(wd * tau / np.pi))
    raise ValueError(model)


def response(model, p, t, du):
    """yhat (without y0) of the model with parameters p for the input du."""
    if np.all(du == du[0]):
        return p[0] * du[0] * step_response(model, p, t - t[0] - p[-1])
    if not uniform(t):
        raise ValueError("a non-uniform record must be a step record")
    return peer.simulate(model, p, du, (t[-1] - t[0]) / (len(t) - 1))


def parameters(model, q):
    """The model's parameters (Kp = 1) from the nonlinear coordinates q."""
    if model == "p1d":
        return [1.0, np.exp(q[0]), q[1]]
    if model == "p2d":
        return [1.0, np.exp(q[0]), np.exp(q[1]), q[2]]
    return [1.0, np.exp(q[0]), q[1], q[2]]


def projected(model, q, t, du, dy):
    """The residuals at q with Kp and the output offset by least squares, and
    (Kp, offset)."""
    g = response(model, parameters(model, q), t, du)
    a = np.column_stack([g, np.ones_like(g)])
    beta, *_ = np.linalg.lstsq(a, dy, rcond=None)
    return dy - a @ beta, beta


def bounds(model, t):
    dt = (t[-1] - t[0]) / (len(t) - 1)
    length = t[-1] - t[0]
    lo_t, hi_t = np.log(dt / 1e3), np.log(1e3 * length)
    if model == "p1d":
        return [lo_t, 0.0], [hi_t, length / 2]
    if model == "p2d":
        return [lo_t, lo_t, 0.0], [hi_t, hi_t, length / 2]
    return [lo_t, MIN_ZETA, 0.0], [hi_t, MAX_ZETA, length / 2]


def starts(model, t):
    """The grid of starts: time constants log-spaced over [dt, T/2], delays
    over [0, T/4], P2D's second lag a fraction of the first, P2DU's Zeta."""
    dt = (t[-1] - t[0]) / (len(t) - 1)
    length = t[-1] - t[0]
    taus = np.log(np.geomspace(dt, length / 2, 5))
    delays = [0.0, dt, 3 * dt, length / 8, length / 4]
    out = []
    for tau in taus:
        for td in delays:
            if model == "p1d":
                out.append([tau, td])
            elif model == "p2d":
                for f in (0.02, 0.2, 0.6):
                    out.append([tau, tau + np.log(f), td])
            else:
                for z in (0.2, 0.6, 0.95):
                    out.append([tau, z, td])
    return out


def solve(model, q0, t, du, dy, fixed_delay=None):
    lo, hi = bounds(model, t)
    q0 = np.clip(np.array(q0, dtype=float), lo, hi)
    if fixed_delay is not None:

        def fun(r):
            return projected(model, np.append(r, fixed_delay), t, du, dy)[0]

        r = optimize.least_squares(fun, q0[:-1], bounds=(lo[:-1], hi[:-1]), method="trf", jac="3-point",
                                   xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=400)
        return np.append(r.x, fixed_delay), r.cost
    r = optimize.least_squares(lambda q: projected(model, q, t, du, dy)[0], q0, bounds=(lo, hi), method="trf",
                               jac="3-point", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
    return r.x, r.cost


def fit(record, model, u0):
    """The reference fit: a dict of the best cost, the parameters (NAMES
    order), y0, and how many of the starts reached the best within 1e-8."""
    t, u, y = load(record)
    du, dy = u - u0, y - y[0]
    dt = (t[-1] - t[0]) / (len(t) - 1)
    results = [solve(model, q0, t, du, dy) for q0 in starts(model, t)]
    costs = np.array([c for _, c in results])
    q, cost = results[int(np.argmin(costs))]
    # The delay's profile around the best: 0, and quarter samples within
    # three samples of it.
    grid = [0.0] + [q[-1] + k * dt / 4 for k in range(-12, 13) if k != 0]
    for td in [v for v in grid if 0.0 <= v <= (t[-1] - t[0]) / 2]:
        qd, cd = solve(model, np.append(q[:-1], td), t, du, dy, fixed_delay=td)
        if cd < cost:
            q, cost = solve(model, qd, t, du, dy)
            q, cost = (qd, cd) if cd < cost else (q, cost)
    r, (kp, offset) = projected(model, q, t, du, dy)
    p = parameters(model, q)
    p[0] = kp
    if model == "p2d" and p[2] > p[1]:
        p[1], p[2] = p[2], p[1]
    return {
        "record": record, "model": model, "u0": u0, "cost": float(0.5 * r @ r),
        "parameters": dict(zip(NAMES[model], map(float, p))), "y0": float(y[0] + offset),
        "starts": len(results), "starts_at_best": int(np.sum(costs <= cost * (1 + 1e-8))),
    }


def cost_of(record, model, u0, values, y0):
    """1/2 sum (y - y0 - yhat)^2 of the given parameters (NAMES order)."""
    t, u, y = load(record)
    r = y - y0 - response(model, np.asarray(values, dtype=float), t, u - u0)
    return float(0.5 * r @ r)


def realisation(model, p):
    """A, B, C of Kp / den(s) in controllable canonical form (this file's own,
    not pidlab's realisation)."""
    den = np.asarray(peer.denominator(model, p), dtype=float)
    n = len(den) - 1
    a = np.zeros((n, n))
    a[0, :] = -den[1:] / den[0]
    a[1:, :-1] += np.eye(n - 1)
    b = np.zeros(n)
    b[0] = 1.0
    c = np.zeros(n)
    c[-1] = p[0] / den[0]
    return a, b, c


def response_piecewise(model, p, t, du, hold="zoh", before=0.0, free=None):
    """yhat_k (without y0) at the times t of the model with parameters p (NAMES
    order) for the input du = u - u0, integrated exactly piece by piece on any
    grid: the input held over [t_k, t_(k+1)) (hold "zoh") or linear from
    (t_k, du_k) to (t_(k+1), du_(k+1)) ("foh"), held after the last sample,
    and `before` before t[0]; all delayed by Td. The state at t[0] is the one
    whose free response C A^i x, i = 0 .. n-1, is `free` (zeros if None).
    Each piece between the delayed input's breakpoints t_j + Td advances
    [x, w, w'] by expm of [[A, B, 0], [0, 0, 1], [0, 0, 0]] times its length."""
    t = np.asarray(t, dtype=float)
    du = np.asarray(du, dtype=float)
    a, b, c = realisation(model, p)
    n = len(b)
    td = float(p[-1])
    m = np.zeros((n + 2, n + 2))
    m[:n, :n], m[:n, n], m[n, n + 1] = a, b, 1.0
    x = np.zeros(n)
    if free is not None:
        obs = np.array([c @ np.linalg.matrix_power(a, i) for i in range(n)])
        x = np.linalg.solve(obs, np.asarray(free, dtype=float))
    cache = {}

    def advance(x, h, w, slope):
        key = round(h, 12)
        if key not in cache:
            cache[key] = linalg.expm(m * h)
        return (cache[key] @ np.concatenate([x, [w, slope]]))[:n]

    def piece(s):
        """The undelayed input's value and slope on the piece starting at s."""
        if s < t[0]:
            return before, 0.0
        j = min(int(np.searchsorted(t, s, side="right")) - 1, len(t) - 1)
        if hold == "zoh" or j == len(t) - 1:
            return du[j], 0.0
        slope = (du[j + 1] - du[j]) / (t[j + 1] - t[j])
        return du[j] + slope * (s - t[j]), slope

    y = np.zeros(len(t))
    y[0] = c @ x
    shifted = t + td
    for k in range(len(t) - 1):
        cuts = shifted[(shifted > t[k]) & (shifted < t[k + 1])]
        edges = np.concatenate([[t[k]], cuts, [t[k + 1]]])
        for lo, hi in zip(edges[:-1], edges[1:]):
            # The piece's delayed input from its midpoint's sample: no
            # rounding at the breakpoints.
            mid = 0.5 * (lo + hi) - td
            w, slope = piece(mid)
            x = advance(x, hi - lo, w - slope * (mid - (lo - td)), slope)
        y[k + 1] = c @ x
    return y


def cost_of_mode(record, model, values, u0, y0, hold="zoh", before=None, free=None):
    """1/2 sum (y - y0 - yhat)^2 of the given parameters (NAMES order) in any
    mode: the intersample behaviour `hold`, the input before the record
    `before` (u0 if None), the initial state by its free response `free`."""
    t, u, y = load(record)
    before = u0 if before is None else before
    r = y - y0 - response_piecewise(model, np.asarray(values, dtype=float), t, u - u0, hold, before - u0, free)
    return float(0.5 * r @ r)


def main():
    if len(sys.argv) == 3:
        case = next(c for c in CASES if c[:2] == tuple(sys.argv[1:]))
        print(json.dumps(fit(*case), indent=1))
        return
    # Each case written as it is done (kept in the order of CASES).
    fits = {}
    if os.path.exists(REFERENCE):
        with open(REFERENCE) as f:
            fits = {(c["record"], c["model"]): c for c in json.load(f)["fits"]}
    todo = [c for c in CASES if len(sys.argv) < 2 or c[0] in sys.argv[1:]]
    for case in todo:
        fits[case[:2]] = fit(*case)
        print(json.dumps(fits[case[:2]]), flush=True)
        ordered = [fits[c[:2]] for c in CASES if c[:2] in fits]
        with open(REFERENCE, "w") as f:
            json.dump({"generated_by": "tests/python/identify_reference.py", "fits": ordered}, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
