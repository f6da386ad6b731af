#!/usr/bin/python3
"""An independent reference optimum for `pidlab tune --method optimal`.

The problem (docs/tuning.md, "The design engine"): on the continuous loop of
the plant P(s) = G(s) e^(-sL) and C(s) = kp + ki/s + kd s/(tf s + 1) (or a PI,
kd = 0), minimise the integrated absolute error of a unit load step at the
plant input (r = 0, d = 1(t) added to u),

    IAE = int_0^inf |y(t)| dt,   Y(s) = P(s) / (1 + C(s) P(s)) / s,

subject to Ms = ||1/(1+CP)||inf <= M, Mt = ||CP/(1+CP)||inf <= M, the noise
gain ||C/(1+CP)||inf <= Gn, Td = kd/kp <= the plant's dominant time constant
(its slowest stable pole's -1/Re p), N = Td/tf in [2, 50], the closed loop
stable. Nothing is shared with pidlab's C++ (which simulates on a uniform time
grid with matrix exponentials and searches shapes by Nelder-Mead with a
bisection on kp). Here everything is done in the frequency domain:

* The load response by numerical inverse Laplace transform (Bromwich line
  Re s = sigma > 0, the trapezoid rule in omega, i.e. one inverse real FFT):
  y(t_k) e^(-sigma t_k) = (1/T) sum_n Y(sigma + j w_n) e^(j w_n t_k), w_n =
  2 pi n / T, which is exactly the periodised y(t) e^(-sigma t) (Poisson's
  summation formula) truncated at the Nyquist frequency. The dead time is the
  exact e^(-sL) of the transform. The window T is fitted to each design (the
  response died out by 0.6 T, checked), sigma = 4 / T damps what wraps
  around; the IAE is the rectangle (periodic trapezoid) sum of |y_k|, 2^15
  samples (the search: 2^14), reported on 4 x 2^15 with the changes on a
  window twice as long and on 4x the samples (about 1e-6 here; against
  scipy.signal.step of the rational loop without dead time, 1e-9). Its
  gradient in the parameters is exact for that sum (dY = -Y P S dC, by the
  adjoint of the inverse FFT: one more FFT).
* Ms, Mt and the noise gain on a frequency grid (Grid): 1 + L itself on a
  log grid, a linear grid around the plant's phase crossover and, with a
  dead time, a linear grid resolving the ripple of e^(-jwL) (30 points per
  2 pi / L; 60 for the reported peaks) up to 60/L (2000/L); above that,
  where the phase of e^(-jwL) turns through 2 pi in a few per cent of w, the
  envelope over that phase (|S| <= 1/(1-|L|), ...), tight there. The
  high-frequency limit of |C S| (kp + kd/tf) is a constraint of its own; the
  reported peaks refine each local maximum by a bounded scalar search.
* Stability by the Nyquist criterion: the winding of 1 + C P around 0 along
  the imaginary axis (indented to the right of the integrators at s = 0),
  unwrapped on the grid; the plants taken are open-loop stable apart from
  poles at the origin, so the closed loop is stable iff the winding is 0
  (and |L| < 0.9 where the grid uses the envelope).
* The optimum by scipy's SLSQP in x = log(kp, ki, Td, N) (PI: log(kp, ki))
  with the peaks at every grid point as smooth inequality constraints
  (log M - log|S(j w_i)| >= 0, ...; analytic Jacobians), Td and N as box
  bounds, from seven deterministic starts (the AMIGO rule's PID on a
  first-order-plus-dead-time model by the method of areas, or on an
  integrator-plus-dead-time model, and six other shapes of ki/kp, Td and N,
  each scaled in gain to meet the bounds), plus any given (the test passes
  the optimum at the other noise bound); each start is scouted for 25
  iterations, the best two polished to convergence, every SLSQP run redone
  on the window of its result until the window stays. Then an exchange step
  adds the dense grid's peak frequencies to the grid and re-solves, and the
  design is scaled back (all gains x f < 1) until the dense analysis meets
  the bounds within 1e-5. Checked against 40 random starts on 21 of the
  test's cases: the same optimum within 0.02 %.

Usage:
  design_reference.py --num 1 --den 1,3,3,1 [--delay 0] --ms 1.59 --noise 25 [--pi]
      prints the reference optimum as JSON;
  design_reference.py --num ... --den ... --gains kp,ki,kd,tf
      prints the analysis (IAE, Ms, Mt, noise gain, stable) of given gains.
"""

import argparse
import json
import math
import sys
import warnings

import numpy as np
from scipy import optimize, signal

# --------------------------------------------------------------------------
# The plant.


class Plant:
    """G(s) e^(-sL), G = num/den (descending powers of s), strictly proper."""

    def __init__(self, num, den, delay=0.0):
        num = np.trim_zeros(np.atleast_1d(np.asarray(num, float)), "f")
        den = np.trim_zeros(np.atleast_1d(np.asarray(den, float)), "f")
        if len(num) >= len(den):
            raise ValueError("the plant must be strictly proper")
        self.num = num / den[0]
        self.den = den / den[0]
        self.delay = float(delay)
        # Poles at the origin (trailing zero coefficients of den).
        self.integrators = 0
        d = self.den.copy()
        while len(d) > 1 and d[-1] == 0.0:
            d = d[:-1]
            self.integrators += 1
        self.den_reduced = d  # den / s^integrators
        self.poles = np.roots(self.den)

    def g(self, s):
        """G(s) e^(-sL) at complex s (array)."""
        return np.polyval(self.num, s) / np.polyval(self.den, s) * np.exp(-s * self.delay)

    def static_gain(self):
        """K of a stable plant, Kv (the velocity gain) of an integrating one."""
        return self.num[-1] / self.den_reduced[-1]

    def dominant_time_constant(self):
        """-1/Re p of the slowest stable pole off the origin."""
        tcs = [-1.0 / p.real for p in self.poles if p.real < 0.0 and abs(p) > 1e-12]
        if tcs:
            return max(tcs)
        # No stable pole: the slowest of its times (the delay, the zeros').
        return self.time_scales()[1]

    def time_scales(self):
        """(fast, slow): the fastest and slowest of the delay and the poles'
        and zeros' time constants."""
        ts = [1.0 / abs(p) for p in self.poles if abs(p) > 1e-12]
        ts += [1.0 / abs(z) for z in np.roots(self.num) if abs(z) > 1e-12] if len(self.num) > 1 else []
        if self.delay > 0:
            ts.append(self.delay)
        if not ts:
            ts = [1.0]
        return min(ts), max(ts)

    def phase_crossover(self):
        """The lowest frequency where arg G(jw) e^(-jwL) = -180 deg (or None)."""
        fast, slow = self.time_scales()
        w = np.logspace(math.log10(1e-3 / slow), math.log10(1e3 / fast), 20000)
        ph = np.unwrap(np.angle(self.g(1j * w)))
        # At w -> 0+ the phase is -90 deg per integrator (a positive gain).
        target0 = -self.integrators * np.pi / 2
        ph = ph + 2.0 * np.pi * round((target0 - ph[0]) / (2.0 * np.pi))
        idx = np.nonzero(ph <= -np.pi)[0]
        if len(idx) == 0:
            return None
        i = idx[0]
        if i == 0:
            return w[0]
        t = (-np.pi - ph[i - 1]) / (ph[i] - ph[i - 1])
        return math.exp(math.log(w[i - 1]) + t * (math.log(w[i]) - math.log(w[i - 1])))


# --------------------------------------------------------------------------
# The controller, as x = log(kp, ki, Td, N) (PID) or log(kp, ki) (PI).


def gains_of(x, pi):
    if pi:
        return dict(kp=math.exp(x[0]), ki=math.exp(x[1]), kd=0.0, tf=0.0)
    kp, ki, td, n = (math.exp(v) for v in x)
    return dict(kp=kp, ki=ki, kd=kp * td, tf=td / n)


def x_of(gains, pi):
    kp, ki, kd, tf = gains["kp"], gains["ki"], gains["kd"], gains["tf"]
    if pi:
        return np.log([kp, ki])
    td = kd / kp
    return np.log([kp, ki, td, td / tf])


def c_and_grad(x, s, pi):
    """C(s) and dC/dx_i (rows), x the log parameters."""
    if pi:
        kp, ki = math.exp(x[0]), math.exp(x[1])
        c = kp + ki / s
        return c, np.array([kp * np.ones_like(s), ki / s])
    kp, ki, td, n = (math.exp(v) for v in x)
    q = td * s / n + 1.0  # tf s + 1
    d = kp * td * s / q  # the filtered derivative
    c = kp + ki / s + d
    dd_td = kp * td * s / q ** 2  # d D / d log Td
    dd_n = d * (td * s / n) / q  # d D / d log N
    return c, np.array([kp + d, ki / s, dd_td, dd_n])


def c_of_gains(g, s):
    c = g["kp"] + g["ki"] / s
    if g["kd"] != 0.0:
        c = c + g["kd"] * s / (g["tf"] * s + 1.0)
    return c


def c_inf(g):
    """lim |C(jw)|, w -> inf."""
    return g["kp"] + (g["kd"] / g["tf"] if g["kd"] != 0.0 else 0.0)


# --------------------------------------------------------------------------
# The load response by the inverse FFT of Y on a Bromwich line.


class Window:
    """The transform grid of one window length T with n samples."""

    def __init__(self, plant, T, n):
        self.T, self.n = float(T), int(n)
        self.sigma = 4.0 / self.T
        w = 2.0 * np.pi / self.T * np.arange(self.n // 2 + 1)
        self.s = self.sigma + 1j * w
        self.p = plant.g(self.s)
        self.h = self.T / self.n
        self.t = np.arange(self.n) * self.h
        self.growth = np.exp(self.sigma * self.t)
        self.scale = self.n / self.T
        self.adjoint_weights = np.full(self.n // 2 + 1, 2.0)
        self.adjoint_weights[0] = self.adjoint_weights[-1] = 1.0

    def y_of_c(self, c):
        return self.y_of_transform(self.p / (1.0 + c * self.p) / self.s)

    def y_of_transform(self, yt):
        return np.fft.irfft(yt, n=self.n, axis=-1) * self.scale * self.growth

    def iae_and_grad(self, x, pi):
        """The IAE h sum |y_k| and its gradient in x (exact for the sum):
        with dY_i = -Y P S dC/dx_i and y = a irfft(Y) (a = scale x growth),
        dIAE_i = h sum_k sign(y_k) a_k irfft(dY_i)_k, by the adjoint of the
        inverse real FFT: (1/n) Re sum_m c_m dY_i,m conj(W_m), W = rfft(w),
        w = h a sign(y), c_m = 2 but 1 at m = 0 and n/2."""
        c, dc = c_and_grad(x, self.s, pi)
        sens = 1.0 / (1.0 + c * self.p)
        yt = self.p * sens / self.s
        y = self.y_of_transform(yt)
        iae = self.h * np.sum(np.abs(y))
        wt = np.fft.rfft(self.h * self.scale * self.growth * np.sign(y))
        wt *= self.adjoint_weights
        grad = np.real((-(yt * self.p * sens)[None, :] * dc) @ np.conj(wt)) / self.n
        return iae, grad, y

    def iae_of_gains(self, g):
        y = self.y_of_c(c_of_gains(g, self.s))
        return self.h * np.sum(np.abs(y)), y


# --------------------------------------------------------------------------
# Frequency grids, peaks and stability.


class Grid:
    """The frequencies (rad/s) the peaks are taken on.

    `exact`: 1 + L(jw) itself, on a log grid from eps (the Nyquist
    indentation's radius) and, with a dead time, a linear grid of spacing
    2 pi / (L k) (k points per ripple of e^(-jwL)) up to w_env, plus a linear
    grid around the plant's phase crossover w_ref. `env` (dead time only): a
    log grid from w_env up, where the delay's phase turns through pi in a few
    per cent of w, so the peak over each ripple is the envelope over the phase
    of L: |S| <= 1/(1-|L|), |T| <= |L|/(1-|L|), |C S| <= |C|/(1-|L|) (tight
    there; |L| < 1 is required there, a stable loop has it). The top is where
    Gn |G(jw)| < 1e-6 (|C| <= about Gn), at least 1e4 w_ref."""

    def __init__(self, plant, noise, w_ref, dense=False):
        fast, slow = plant.time_scales()
        self.eps = 1e-4 * min(w_ref, 1.0 / slow)
        gn = noise if np.isfinite(noise) else 1e6
        wide = np.logspace(math.log10(w_ref), math.log10(w_ref) + 10, 5000)
        above = np.nonzero(gn * np.abs(plant.g(1j * wide)) >= 1e-6)[0]
        w_hi = max(wide[above[-1]] if len(above) else w_ref, 1e4 * w_ref)
        per_decade = 400 if dense else 50
        near = np.linspace(0.02 * w_ref, 5.0 * w_ref, 2000 if dense else 200)
        if plant.delay > 0:
            ripples = 2000.0 if dense else 60.0
            w_env = min(max(ripples / plant.delay, 20.0 * w_ref), w_hi)
            step = 2.0 * np.pi / plant.delay / (60.0 if dense else 30.0)
            lin = np.arange(step, w_env, step)
        else:
            w_env = w_hi
            lin = np.zeros(0)
        logx = np.logspace(math.log10(self.eps), math.log10(w_env),
                           max(int(per_decade * math.log10(w_env / self.eps)), 50))
        self.exact = np.unique(np.concatenate([logx, lin, near[near < w_env]]))
        if w_env < w_hi:
            self.env = np.logspace(math.log10(w_env), math.log10(w_hi),
                                   max(int(per_decade * math.log10(w_hi / w_env)), 10))[1:]
        else:
            self.env = np.zeros(0)
        self._plant_values(plant)

    def _plant_values(self, plant):
        """The plant's G(s) e^(-sL) on the grid, once."""
        self.s_semi = self.eps * np.exp(1j * np.linspace(-np.pi / 2, np.pi / 2, 181))
        self.p_semi = plant.g(self.s_semi)
        self.s_exact, self.s_env = 1j * self.exact, 1j * self.env
        self.p_exact, self.p_env = plant.g(self.s_exact), plant.g(self.s_env)

    def with_points(self, plant, extra):
        """A copy with more exact points (those below the envelope's start)."""
        g = Grid.__new__(Grid)
        g.eps, g.env = self.eps, self.env
        top = self.exact[-1]
        extra = np.asarray([v for v in extra if 0 < v < top])
        g.exact = np.unique(np.concatenate([self.exact, extra, extra * (1 - 1e-4), extra * (1 + 1e-4)]))
        g._plant_values(plant)
        return g


def winding_unstable(c_fn, plant, grid):
    """The number of closed-loop poles in the closed right half plane by the
    Nyquist criterion: the change of arg(1 + L) along the imaginary axis, up
    from -j inf to j inf, indented to the right of s = 0 by a half circle of
    radius eps, and back by the right half plane's big half circle (where
    L -> 0) is -2 pi Z (the plants are open-loop stable but for poles at the
    origin, which the indentation leaves out). Taken on the exact grid; past
    it, in the envelope grid, |L| < 0.9 is required (so 1 + L stays in the
    right half plane: no more turns). Returns (Z, ok), ok false when the grid
    is too coarse to unwrap the phase or |L| is not small beyond it."""
    f_semi = 1.0 + c_fn(grid.s_semi) * grid.p_semi
    f_up = 1.0 + c_fn(grid.s_exact) * grid.p_exact
    a_semi = np.unwrap(np.angle(f_semi))
    a_up = np.unwrap(np.angle(f_up))
    steps = np.abs(np.diff(a_up))
    ok = len(steps) == 0 or np.max(steps) < 0.75 * np.pi
    ok = ok and np.max(np.abs(np.diff(a_semi))) < 0.75 * np.pi
    if len(grid.env):
        ok = ok and np.max(np.abs(c_fn(grid.s_env) * grid.p_env)) < 0.9
    else:
        ok = ok and abs(f_up[-1] - 1.0) < 0.9
    # j w_top -> j inf: 1 + L -> 1 inside the right half plane.
    delta_upper = (a_up[-1] - a_up[0]) - np.angle(f_up[-1])
    total = (a_semi[-1] - a_semi[0]) + 2.0 * delta_upper
    z = -total / (2.0 * np.pi)
    return int(round(z)), bool(ok and abs(z - round(z)) < 0.05)


def refine_peak(fn, w, vals, most=25):
    """The largest value of fn (of one w > 0) near the grid's local maxima
    (the `most` highest within 3 % of the top), by a bounded scalar search
    in log w between the neighbours."""
    n = len(w)
    if n == 0:
        return -math.inf, math.nan
    best = float(np.max(vals))
    best_w = float(w[int(np.argmax(vals))])
    inner = (vals[1:-1] >= vals[:-2]) & (vals[1:-1] >= vals[2:])
    cand = list(np.nonzero(inner)[0] + 1)
    if n > 1 and vals[0] >= vals[1]:
        cand.append(0)
    if n > 1 and vals[-1] >= vals[-2]:
        cand.append(n - 1)
    cand = [i for i in cand if vals[i] >= 0.97 * best]
    cand.sort(key=lambda i: -vals[i])
    for i in cand[:most]:
        lo = math.log(w[max(i - 1, 0)])
        hi = math.log(w[min(i + 1, n - 1)])
        if hi <= lo:
            continue
        r = optimize.minimize_scalar(lambda lw: -fn(math.exp(lw)), bounds=(lo, hi), method="bounded",
                                     options=dict(xatol=1e-9))
        if -r.fun > best:
            best, best_w = -r.fun, math.exp(r.x)
    return best, best_w


# --------------------------------------------------------------------------
# The problem: the analysis of one design, and the optimum.


def window_holds(az):
    """|z| = |y e^(-sigma t)| on a window has died out by its end: the last
    tenth's median below 1e-5 of its largest, and the last 3 % below 1e-4."""
    n = len(az)
    top = np.max(az)
    return np.median(az[int(0.9 * n):]) <= 1e-5 * top and np.max(az[int(0.97 * n):]) <= 1e-4 * top


class Problem:
    VIOLATION_TOL = 1e-5
    SEARCH_N = 1 << 14  # samples of the search's windows (the reported IAE: 4 x 2^15)
    SCOUT_ITER = 25  # SLSQP iterations from each start before the best two are polished

    def __init__(self, plant, ms=1.59, mt=None, noise=np.inf, pi=False, td_max=None):
        self.plant = plant
        self.ms = float(ms)
        self.mt = float(mt if mt is not None else ms)
        self.noise = float(noise)
        self.pi = bool(pi)
        self.td_max = float(td_max if td_max is not None else plant.dominant_time_constant())
        self.n_min, self.n_max = 2.0, 50.0
        w180 = plant.phase_crossover()
        fast, slow = plant.time_scales()
        self.w_ref = w180 if w180 is not None else 1.0 / fast
        self.grid = Grid(plant, self.noise, self.w_ref)
        self.dense = Grid(plant, self.noise, self.w_ref, dense=True)
        self._windows = {}
        self.evaluations = 0

    # -- the load response ---------------------------------------------
    def window(self, T, n):
        key = (round(math.log(T), 9), n)
        win = self._windows.pop(key, None) or Window(self.plant, T, n)
        self._windows[key] = win  # the most recent last
        while len(self._windows) > 24:
            self._windows.pop(next(iter(self._windows)))
        return win

    def fit_window(self, g, T=None, n=1 << 15):
        """A window (T, n) that holds the load response of g: judged on
        z = y e^(-sigma t) (the transform's own output, its small noise floor
        from the truncation at the Nyquist frequency not amplified), the last
        tenth of the window below 1e-5 of max |z| and the response's end (the
        last |z| above that) in [0.3, 0.6] of T, for the resolution."""
        if T is None:
            T = 60.0 * (self.plant.delay + 2.0 / self.w_ref)
        for _ in range(60):
            win = self.window(T, n)
            z = win.y_of_c(c_of_gains(g, win.s)) / win.growth
            if not np.all(np.isfinite(z)):
                return None
            az = np.abs(z)
            thr = 1e-5 * np.max(az)
            if not window_holds(az):
                T *= 2.0
                continue
            above = np.nonzero(az > thr)[0]
            end = (above[-1] + 1) * win.h if len(above) else win.h
            if end < 0.3 * T:
                T = max(end / 0.45, 1e-9)
                continue
            if end > 0.6 * T:
                T *= 1.5
                continue
            return T, n
        return T, n

    def iae(self, g, check=True):
        """The load IAE of g on a fitted window, with the relative changes on
        a window twice as long and on four times the samples: (iae, info)."""
        fit = self.fit_window(g)
        if fit is None:
            return math.inf, {}
        T, n = fit
        iae1, _ = self.window(T, n).iae_of_gains(g)
        info = dict(window_s=T, samples=n)
        if check:
            iae2, _ = self.window(2.0 * T, 2 * n).iae_of_gains(g)
            iae3, _ = self.window(T, 4 * n).iae_of_gains(g)
            info["change_longer"] = abs(iae2 - iae1) / iae1
            info["change_finer"] = abs(iae3 - iae1) / iae1
            iae1 = iae3
        return iae1, info

    # -- the peaks ------------------------------------------------------
    def peaks(self, g, grid=None):
        grid = self.dense if grid is None else grid
        p = self.plant

        def parts(wv):
            s = 1j * wv
            c = c_of_gains(g, s)
            return c, c * p.g(s)

        def s_at(wv):
            c, l = parts(wv)
            return abs(1.0 / (1.0 + l))

        def t_at(wv):
            c, l = parts(wv)
            return abs(l / (1.0 + l))

        def n_at(wv):
            c, l = parts(wv)
            return abs(c / (1.0 + l))

        c = c_of_gains(g, grid.s_exact)
        l = c * grid.p_exact
        out = {}
        for name, fn, vals in (("ms", s_at, np.abs(1.0 / (1.0 + l))), ("mt", t_at, np.abs(l / (1.0 + l))),
                               ("noise_gain", n_at, np.abs(c / (1.0 + l)))):
            out[name], out[name + "_rad_s"] = refine_peak(fn, grid.exact, vals)
        if len(grid.env):
            c = c_of_gains(g, grid.s_env)
            al = np.abs(c * grid.p_env)
            gap = np.maximum(1.0 - al, 1e-300)
            for name, vals in (("ms", 1.0 / gap), ("mt", al / gap), ("noise_gain", np.abs(c) / gap)):
                i = int(np.argmax(vals))
                if vals[i] > out[name]:
                    out[name], out[name + "_rad_s"] = float(vals[i]), float(grid.env[i])
        if c_inf(g) > out["noise_gain"]:
            out["noise_gain"], out["noise_gain_rad_s"] = c_inf(g), math.inf
        unstable, ok = winding_unstable(lambda s: c_of_gains(g, s), p, grid)
        out.update(unstable_poles=unstable, nyquist_ok=ok, stable=bool(ok and unstable == 0))
        return out

    def analyse(self, g, with_iae=True):
        out = self.peaks(g)
        out["td"] = g["kd"] / g["kp"] if g["kd"] != 0.0 else 0.0
        out["n"] = out["td"] / g["tf"] if g["kd"] != 0.0 and g["tf"] > 0 else math.inf
        out["td_bound"] = self.td_max
        if with_iae and out["stable"]:
            out["iae"], out["iae_info"] = self.iae(g)
        elif with_iae:
            out["iae"], out["iae_info"] = math.inf, {}
        return out

    def violations(self, a):
        """The relative excess over each bound (<= 0: met)."""
        v = dict(ms=a["ms"] / self.ms - 1.0, mt=a["mt"] / self.mt - 1.0,
                 noise_gain=a["noise_gain"] / self.noise - 1.0)
        if a["td"] > 0:
            v.update(td=a["td"] / self.td_max - 1.0, n_max=a["n"] / self.n_max - 1.0,
                     n_min=self.n_min / a["n"] - 1.0)
        v["stable"] = 0.0 if a["stable"] else math.inf
        return v

    def violation(self, a):
        return max(self.violations(a).values())

    # -- the constraint set on a grid ----------------------------------
    def constraints(self, x, grid):
        """(values, jacobian) of the peak constraints on the grid, every one
        >= 0 when met: log bound - log |.| on the exact grid, the envelopes
        and |L| <= 0.5 on the envelope grid, and log Gn - log |C(j inf)|."""
        vals, jac = [], []
        lms, lmt = math.log(self.ms), math.log(self.mt)
        lgn = math.log(self.noise) if np.isfinite(self.noise) else None
        c, dc = c_and_grad(x, grid.s_exact, self.pi)
        p = grid.p_exact
        l = c * p
        f = 1.0 + l
        dlogf = np.real(dc * p[None, :] / f[None, :]).T  # d log|1+L|
        dlogc = np.real(dc / c[None, :]).T  # d log|C| = d log|L|
        logf = np.log(np.abs(f))
        vals += [lms + logf, lmt - np.log(np.abs(l)) + logf]
        jac += [dlogf, dlogf - dlogc]
        if lgn is not None:
            vals.append(lgn - np.log(np.abs(c)) + logf)
            jac.append(dlogf - dlogc)
        if len(grid.env):
            c, dc = c_and_grad(x, grid.s_env, self.pi)
            al = np.abs(c * grid.p_env)
            dlogc = np.real(dc / c[None, :]).T
            gap = np.maximum(1.0 - al, 1e-12)
            loggap = np.log(gap)
            dloggap = -(al / gap)[:, None] * dlogc
            vals += [lms + loggap, lmt - np.log(al) + loggap, math.log(0.5) - np.log(al)]
            jac += [dloggap, dloggap - dlogc, -dlogc]
            if lgn is not None:
                vals.append(lgn - np.log(np.abs(c)) + loggap)
                jac.append(dloggap - dlogc)
        if lgn is not None:
            # |C(j inf)| = kp (1 + N) (PID), kp (PI).
            if self.pi:
                vals.append(np.array([lgn - x[0]]))
                jac.append(np.array([[-1.0, 0.0]]))
            else:
                nn = math.exp(x[3])
                vals.append(np.array([lgn - x[0] - math.log1p(nn)]))
                jac.append(np.array([[-1.0, 0.0, 0.0, -nn / (1.0 + nn)]]))
        return np.concatenate(vals), np.vstack(jac)

    def stable_x(self, x, grid):
        g = gains_of(x, self.pi)
        unstable, ok = winding_unstable(lambda s: c_of_gains(g, s), self.plant, grid)
        return ok and unstable == 0

    def bounds(self):
        if self.pi:
            return [(-30.0, 30.0), (-30.0, 30.0)]
        return [(-30.0, 30.0), (-30.0, 30.0), (math.log(self.td_max) - 9.0, math.log(self.td_max)),
                (math.log(self.n_min), math.log(self.n_max))]

    # -- starts -------------------------------------------------------
    def fopdt(self):
        """(K, T, L) of a first-order-plus-dead-time model by the method of
        areas (Astrom & Hagglund): Tar = A0/K from the moments, T = e A1/K
        with A1 the area under the step response up to Tar."""
        p = self.plant
        K = p.static_gain()
        num_asc, den_asc = p.num[::-1], p.den[::-1]
        tar = p.delay + den_asc[1] / den_asc[0] - (num_asc[1] / num_asc[0] if len(num_asc) > 1 else 0.0)
        t = np.linspace(0.0, max(tar - p.delay, 1e-9), 4001)
        _, ystep = signal.step(signal.lti(p.num, p.den), T=t)
        a1 = np.trapz(ystep, t)
        T = max(math.e * a1 / K, 1e-6 * tar)
        L = max(tar - T, 1e-3 * tar)
        return K, T, L

    def amigo_shape(self):
        """AMIGO's PID (Astrom & Hagglund 2006) on the plant's FOPDT model,
        or on its integrator-plus-dead-time model: (kp, ki, Td)."""
        p = self.plant
        if p.integrators >= 1:
            kv = p.static_gain()
            den = p.den_reduced
            lag = den[-2] / den[-1] if len(den) > 1 else 0.0
            L = max(p.delay + lag, 1e-3)  # e^(-sL)/(s(1+T1 s)) ~ e^(-s(L+T1))/s
            kp = 0.45 / (kv * L)
            return kp, kp / (8.0 * L), 0.5 * L
        K, T, L = self.fopdt()
        kp = (0.2 + 0.45 * T / L) / K
        ti = (0.4 * L + 0.8 * T) / (L + 0.1 * T) * L
        td = 0.5 * L * T / (0.3 * L + T)
        return kp, kp / ti, td

    def feasible_on(self, x, grid):
        vals, _ = self.constraints(x, grid)
        return np.min(vals) >= 0.0 and self.stable_x(x, grid)

    def scale_to_bounds(self, x):
        """Shift log kp and log ki together (Td, N kept) to the largest gain
        that meets the constraints on the grid and is stable (bisection)."""
        x = np.array(x, float)

        def ok(a):
            y = x.copy()
            y[:2] += a
            return self.feasible_on(y, self.grid)

        if ok(0.0):
            lo, hi = 0.0, 0.25
            while ok(hi) and hi < 30:
                lo, hi = hi, hi * 2.0
        else:
            hi, lo = 0.0, -0.25
            while not ok(lo) and lo > -30:
                hi, lo = lo, lo * 2.0
            if not ok(lo):
                return None
        while hi - lo > 1e-4:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if ok(mid) else (lo, mid)
        y = x.copy()
        y[:2] += lo
        return y

    def starts(self):
        """Deterministic starts: AMIGO's gains and other shapes around them
        (ki/kp, Td, N), each scaled to meet the bounds on the grid."""
        kp, ki, td = self.amigo_shape()
        if self.pi:
            xs = [np.log([kp, ki * f]) for f in (1.0, 2.0, 0.5, 4.0)]
        else:
            td_a = min(td, self.td_max)
            xs = [np.log([kp, ki * kif, min(td_a * tdf, self.td_max), nn])
                  for tdf, nn, kif in ((1.0, 10.0, 1.0), (0.3, 5.0, 1.5), (3.0, 20.0, 1.0), (1.0, 40.0, 0.5),
                                       (0.1, 3.0, 2.0), (1e3, 50.0, 1.0), (1.0, 50.0, 3.0))]
        out = []
        for x in xs:
            x = np.clip(x, [b[0] for b in self.bounds()], [b[1] for b in self.bounds()])
            y = self.scale_to_bounds(x)
            if y is not None:
                out.append(y)
        return out

    # -- the optimisation -----------------------------------------------
    def solve_from(self, x0, win, grid, maxiter=100):
        """SLSQP from x0 with the window win and the constraint grid. The
        best x seen that meets the constraints on the grid, is stable and
        whose response the window holds (window_holds), and its IAE on win
        (None, inf: none seen)."""
        best = [None, math.inf]
        cache = {}

        def ev(x):
            key = x.tobytes()
            if key not in cache:
                self.evaluations += 1
                cv, cj = self.constraints(x, grid)
                stable = self.stable_x(x, grid)
                if stable:
                    iae, grad, y = win.iae_and_grad(x, self.pi)
                    f, fg = math.log(iae), grad / iae
                    held = window_holds(np.abs(y / win.growth))
                else:  # a wall the line search backs off from
                    iae, f, fg, held = math.inf, 50.0, np.zeros_like(x), False
                cache.clear()
                cache[key] = (f, fg, cv, cj)
                if held and np.min(cv) >= -1e-9 and iae < best[1]:
                    best[0], best[1] = x.copy(), iae
            return cache[key]

        bnds = self.bounds()
        x0 = np.clip(np.asarray(x0, float), [b[0] for b in bnds], [b[1] for b in bnds])
        ev(x0)
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # SLSQP's "clipping to bounds"
            try:
                optimize.minimize(lambda x: ev(x)[0], x0, jac=lambda x: ev(x)[1], method="SLSQP", bounds=bnds,
                                  constraints=[dict(type="ineq", fun=lambda x: ev(x)[2], jac=lambda x: ev(x)[3])],
                                  options=dict(maxiter=maxiter, ftol=1e-10))
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                pass
        return best[0], best[1]

    def run(self, x0, grid, maxiter=100, rounds=4):
        """solve_from on the window fitted to the response of x0, then again
        from its result on the window fitted to that, until the window stays
        (within 20 %). Returns (x, IAE on the result's own fitted window) or
        (None, inf)."""
        x, fit = np.asarray(x0, float), self.fit_window(gains_of(x0, self.pi), n=self.SEARCH_N)
        if fit is None:
            return None, math.inf
        found = None
        for _ in range(rounds):
            x2, _ = self.solve_from(x, self.window(*fit), grid, maxiter)
            if x2 is None:
                break
            found = x = x2
            fit2 = self.fit_window(gains_of(x, self.pi), fit[0], n=self.SEARCH_N)
            if fit2 is None:
                return None, math.inf
            if abs(math.log(fit2[0] / fit[0])) <= 0.2:
                break
            fit = fit2
        if found is None:
            return None, math.inf
        return found, self.iae(gains_of(found, self.pi), check=False)[0]

    def optimise(self, extra_starts=(), verbose=False):
        """The reference optimum: dict(gains, iae, analysis, starts,
        evaluations), or None when no start meets the bounds."""
        starts = [np.asarray(x, float) for x in extra_starts] + self.starts()
        # Scout from every start, then polish the best two distinct ones.
        scouts = []
        for x0 in starts:
            x, v = self.run(x0, self.grid, maxiter=self.SCOUT_ITER, rounds=2)
            if x is not None:
                scouts.append((v, x))
            if verbose:
                print("  start", gains_of(x0, self.pi), "->", x is not None and gains_of(x, self.pi), v,
                      file=sys.stderr)
        scouts.sort(key=lambda r: r[0])
        chosen = []
        for v, x in scouts:
            if all(np.max(np.abs(x - y)) > 1e-3 for _, y in chosen):
                chosen.append((v, x))
            if len(chosen) == 2:
                break
        results = []
        for v0, x0 in chosen:
            x, v = self.run(x0, self.grid)
            results.append((v, x) if x is not None and v <= v0 else (v0, x0))
            if verbose:
                print("  polish", gains_of(x0, self.pi), v0, "->", gains_of(results[-1][1], self.pi),
                      results[-1][0], file=sys.stderr)
        if not results:
            return None
        results.sort(key=lambda r: r[0])
        v, x = results[0]
        # Exchange: the dense analysis's peak frequencies join the grid.
        grid = self.grid
        for _ in range(3):
            g = gains_of(x, self.pi)
            a = self.analyse(g, with_iae=False)
            if self.violation(a) <= self.VIOLATION_TOL:
                break
            grid = grid.with_points(self.plant, [a[k] for k in ("ms_rad_s", "mt_rad_s", "noise_gain_rad_s")
                                     if np.isfinite(a[k])])
            x2, v2 = self.run(x, grid, maxiter=50)
            if x2 is not None:
                x, v = x2, v2
        # Scale back (all gains x f) until the dense analysis meets the bounds.
        g = gains_of(x, self.pi)
        a = self.analyse(g, with_iae=False)
        f = 1.0
        while self.violation(a) > self.VIOLATION_TOL and f > 0.5:
            f *= 0.9995
            g = dict(gains_of(x, self.pi))
            g.update(kp=g["kp"] * f, ki=g["ki"] * f, kd=g["kd"] * f)
            a = self.analyse(g, with_iae=False)
        a = self.analyse(g)
        return dict(gains=g, iae=a["iae"], analysis=a, starts=len(starts), evaluations=self.evaluations)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--num", required=True)
    ap.add_argument("--den", required=True)
    ap.add_argument("--delay", type=float, default=0.0)
    ap.add_argument("--ms", type=float, default=1.59)
    ap.add_argument("--noise", type=float, default=math.inf)
    ap.add_argument("--pi", action="store_true")
    ap.add_argument("--gains", help="kp,ki,kd,tf: analyse these instead")
    ap.add_argument("--verbose", action="store_true")
    a = ap.parse_args(argv)
    plant = Plant([float(v) for v in a.num.split(",")], [float(v) for v in a.den.split(",")], a.delay)
    prob = Problem(plant, a.ms, noise=a.noise, pi=a.pi)
    if a.gains:
        kp, ki, kd, tf = (float(v) for v in a.gains.split(","))
        out = prob.analyse(dict(kp=kp, ki=ki, kd=kd, tf=tf))
    else:
        out = prob.optimise(verbose=a.verbose)
    json.dump(out, sys.stdout, default=float, indent=1)
    print()


if __name__ == "__main__":
    main(sys.argv[1:])
