"""An independent peer of `pidlab identify` in numpy and scipy: the zero-order
hold response of idproc's process models with a fractional input delay, and
their output-error fit by scipy.optimize.least_squares. No pidlab code is used.

The response (Åström and Wittenmark, Computer-Controlled Systems, sec. 2.3):
with the model as x' = A x + B u(t - Td), y = C x, the input held over each
sample and Td = d dt + tau (0 <= tau < dt), the delayed input over
[k dt, (k+1) dt) is u[k-d-1] until k dt + tau and u[k-d] after it, so

    x[k+1] = Phi x[k] + Gamma1 u[k-d-1] + Gamma0 u[k-d],   y[k] = C x[k],
    Phi = e^(A dt),  Gamma0 = int_0^(dt-tau) e^(A s) ds B,
    Gamma1 = e^(A (dt-tau)) int_0^tau e^(A s) ds B,

each from scipy.linalg.expm of the augmented matrix [[A, B], [0, 0]]. The
recursion runs as two linear filters (scipy.signal.lfilter) of u delayed by
d and d + 1 samples.

Used by tests/python/identify_peer_test.py and bench/identify_bench.sh.
"""

import numpy as np
from scipy import linalg, optimize, signal

MODELS = ("p1d", "p2d", "p2du", "p1di")
NAMES = {
    "p1d": ("Kp", "Tp1", "Td"),
    "p2d": ("Kp", "Tp1", "Tp2", "Td"),
    "p2du": ("Kp", "Tw", "Zeta", "Td"),
    "p1di": ("Kp", "Tp1", "Td"),
}


def denominator(model, p):
    """The model's denominator in descending powers of s (numerator: Kp)."""
    if model == "p1d":
        return np.array([p[1], 1.0])
    if model == "p2d":
        return np.polymul([p[1], 1.0], [p[2], 1.0])
    if model == "p2du":
        return np.array([p[1] * p[1], 2.0 * p[2] * p[1], 1.0])
    if model == "p1di":
        return np.array([p[1], 1.0, 0.0])
    raise ValueError(model)


def _hold(a, b, h):
    """e^(A h) and int_0^h e^(A s) ds B."""
    n = a.shape[0]
    m = np.zeros((n + 1, n + 1))
    m[:n, :n], m[:n, n] = a * h, b * h
    e = linalg.expm(m)
    return e[:n, :n], e[:n, n]


def simulate(model, p, du, dt):
    """y[k] - y0 of the model with parameters p (in the order of NAMES) for the
    input du = u - u0 held over each sample, from a zero state."""
    den = denominator(model, p)
    den = den / den[0]
    n = len(den) - 1
    # Controllable canonical form of Kp / den(s).
    a = np.zeros((n, n))
    a[0, :] = -den[1:]
    a[1:, :-1] += np.eye(n - 1)
    b = np.zeros(n)
    b[0] = 1.0
    c = np.zeros(n)
    c[-1] = p[0] / denominator(model, p)[0]
    td = p[-1]
    d = int(np.floor(td / dt))
    tau = td - d * dt
    phi, gamma_rest = _hold(a, b, dt - tau)
    e_tau, gamma_tau = _hold(a, b, tau)
    phi_dt = phi @ e_tau
    gamma0 = gamma_rest
    gamma1 = phi @ gamma_tau
    # y = C (zI - Phi)^-1 (Gamma0 z^-d + Gamma1 z^-(d+1)) u, as filters in z^-1.
    poles = np.poly(phi_dt)
    y = np.zeros(len(du))
    for gamma, shift in ((gamma0, d), (gamma1, d + 1)):
        num, _ = signal.ss2tf(phi_dt, gamma.reshape(-1, 1), c.reshape(1, -1), np.zeros((1, 1)))
        num = np.atleast_1d(num[0])  # descending powers of z: num[0] = 0 (no feedthrough)
        # C (zI - Phi)^-1 gamma = num(z) / poles(z); in z^-1 the leading 0 is one sample of delay.
        if shift >= len(du):
            continue
        shifted = np.concatenate([np.zeros(shift), du[: len(du) - shift]])
        y += signal.lfilter(num, poles, shifted)
    return y


def _gain(model, p, du, dy, dt):
    """The least-squares Kp for the other parameters of p."""
    q = np.array(p, dtype=float)
    q[0] = 1.0
    g = simulate(model, q, du, dt)
    gg = g @ g
    return (g @ dy) / gg if gg > 0 else 1.0


def default_starts(model):
    """A grid of 9 starts: time constants 0.5, 2 and 5 s, delays 0, 0.5 and
    1 s (Kp then by linear least squares); P2D's Tp2 a quarter of Tp1, P2DU's
    Zeta 0.5."""
    starts = []
    for tc in (0.5, 2.0, 5.0):
        for td in (0.0, 0.5, 1.0):
            if model == "p2d":
                starts.append([1.0, tc, tc / 4, td])
            elif model == "p2du":
                starts.append([1.0, tc, 0.5, td])
            else:
                starts.append([1.0, tc, td])
    return starts


def fit(model, t, u, y, starts=None):
    """The output-error fit of `model` to the record (t, u, y) with u0 = u[0]
    and the output offset y0 estimated with the model (pidlab's default), from
    y[0]: least_squares (trf, 3-point differences, bounds) from a grid of
    starts, the best kept. Returns (parameters, cost = 1/2 sum r^2, the
    least_squares result); result.y0 is the estimated y0."""
    t, u, y = (np.asarray(v, dtype=float) for v in (t, u, y))
    dt = (t[-1] - t[0]) / (len(t) - 1)
    length = t[-1] - t[0]
    du, dy = u - u[0], y - y[0]

    def residuals(q):
        return dy - q[-1] - simulate(model, q[:-1], du, dt)

    lower = {"p1d": [-np.inf, dt / 1e3, 0.0], "p2d": [-np.inf, dt / 1e3, dt / 1e3, 0.0],
             "p2du": [-np.inf, dt / 1e3, 1e-3, 0.0], "p1di": [-np.inf, dt / 1e3, 0.0]}[model]
    upper = {"p1d": [np.inf, 1e3 * length, length / 2], "p2d": [np.inf, 1e3 * length, 1e3 * length, length / 2],
             "p2du": [np.inf, 1e3 * length, 1 - 1e-9, length / 2], "p1di": [np.inf, 1e3 * length, length / 2]}[model]
    if starts is None:
        starts = default_starts(model)
    best = None
    for p0 in starts:
        p0 = np.array(p0, dtype=float)
        p0[0] = _gain(model, p0, du, dy, dt)
        q0 = np.append(p0, 0.0)
        r = optimize.least_squares(residuals, q0, bounds=(lower + [-np.inf], upper + [np.inf]), method="trf",
                                   jac="3-point",
                                   x_scale="jac", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
        if best is None or r.cost < best.cost:
            best = r
    p = np.array(best.x[:-1])
    best.y0 = y[0] + best.x[-1]
    if model == "p2d" and p[2] > p[1]:
        p[1], p[2] = p[2], p[1]
    return p, best.cost, best


def step_rich_input(n, rng):
    """At rest for five samples, then levels in [-1, 1] held 3 to 15 samples."""
    u = np.zeros(n)
    k = 5
    while k < n:
        hold = int(rng.integers(3, 16))
        u[k:k + hold] = rng.uniform(-1.0, 1.0)
        k += hold
    return u


def write_csv(path, t, u, y):
    with open(path, "w") as f:
        f.write("t,u,y\n")
        for row in zip(t, u, y):
            f.write("%.17g,%.17g,%.17g\n" % row)
