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
  exact e^(-sL) of the transform. T is chosen per design so that the tail
  past T is negligible (checked), sigma = 4 / T damps what wraps around; the
  IAE is the rectangle (periodic trapezoid) sum of |y_k|. Its gradient in the
  parameters is exact for that sum: dY = -P^2 S^2 dC / s, one more FFT each.
* Ms, Mt and the noise gain on a frequency grid (a log grid plus a linear
  grid up to where Gn |G(jw)| < 0.05, spacing a 60th of the delay's ripple
  2 pi / L), with the analytic high-frequency limit of |C S| (kp + kd/tf)
  added, each local maximum refined by a bounded scalar search for the
  reported peaks.
* Stability by the Nyquist criterion: the winding of 1 + C P around 0 along
  the imaginary axis (indented to the right of the integrators at s = 0),
  unwrapped on the grid; the plants taken are open-loop stable apart from
  poles at the origin, so the closed loop is stable iff the winding is 0.
* The optimum by scipy's SLSQP in x = log(kp, ki, Td, N) (PI: log(kp, ki))
  with the peaks at every grid point as smooth inequality constraints
  (log M - log|S(j w_i)| >= 0, ...; analytic Jacobians), Td and N as box
  bounds, from several deterministic starts (the AMIGO rule's gains on a
  first-order-plus-dead-time model from the plant's moments, and other
  shapes, each scaled to meet the bounds); then an exchange step adds the
  refined peak frequencies to the grid and re-solves, and the best design is
  scaled back (gains x c <= 1) until the refined peaks meet the bounds.

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

import numpy as np
from scipy import optimize, signal

SQRT_EPS = 1e-12


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
        # No stable pole: the delay (the only time the plant has).
        return max(self.delay, 1.0)

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

    def y_of_c(self, c):
        return self.y_of_transform(self.p / (1.0 + c * self.p) / self.s)

    def y_of_transform(self, yt):
        return np.fft.irfft(yt, n=self.n, axis=-1) * self.scale * self.growth

    def iae_and_grad(self, x, pi):
        c, dc = c_and_grad(x, self.s, pi)
        sens = 1.0 / (1.0 + c * self.p)
        yt = self.p * sens / self.s
        y = self.y_of_transform(yt)
        iae = self.h * np.sum(np.abs(y))
        dy = self.y_of_transform(-(yt * self.p * sens)[None, :] * dc)
        grad = self.h * (dy @ np.sign(y))
        return iae, grad, y

    def iae_of_gains(self, g):
        y = self.y_of_c(c_of_gains(g, self.s))
        return self.h * np.sum(np.abs(y)), y


def tail_fraction(y, h, iae, frac=0.25):
    """The share of the IAE in the last `frac` of the window."""
    k = int(len(y) * (1.0 - frac))
    return h * np.sum(np.abs(y[k:])) / max(iae, 1e-300)


def settle_time(y, h, iae, rel=1e-7):
    """The time after which the remaining int |y| is below rel * IAE."""
    tail = np.cumsum(np.abs(y[::-1]))[::-1] * h
    idx = np.nonzero(tail > rel * iae)[0]
    return (idx[-1] + 1) * h if len(idx) else h


# --------------------------------------------------------------------------
# Frequency grids, peaks and stability.


def freq_grid(plant, noise_bound, w_ref, n_log=2400, lin_per_ripple=60, max_lin=20000):
    """The grid the peaks are taken on (rad/s, increasing)."""
    fast, slow = plant.time_scales()
    w_lo = min(1e-4 * w_ref, 1e-3 / slow)
    # Where Gn |G(jw)| falls below 0.05 for good (|L| <= 0.053 beyond: |S|,
    # |T| far below any bound), at least 30 x w_ref.
    wide = np.logspace(math.log10(w_ref), math.log10(w_ref) + 8, 4000)
    gn = noise_bound if np.isfinite(noise_bound) else 1e6
    mag = gn * np.abs(plant.g(1j * wide))
    above = np.nonzero(mag >= 0.05)[0]
    w_nb = wide[above[-1]] if len(above) else w_ref
    w_nb = max(w_nb, 30.0 * w_ref)
    w_hi = 1e3 * w_nb
    grid = [np.logspace(math.log10(w_lo), math.log10(w_hi), n_log)]
    # Linear: near the crossover, and (the delay's ripple) up to w_nb.
    step = w_ref / 200.0
    if plant.delay > 0:
        step = min(step, 2.0 * np.pi / plant.delay / lin_per_ripple)
    top = min(w_nb * 1.2, step * max_lin)
    grid.append(np.arange(step, top, step))
    # Finer around the crossover region.
    grid.append(np.linspace(0.05 * w_ref, 5.0 * w_ref, 1500))
    w = np.unique(np.concatenate(grid))
    return w


def winding_unstable(c_fn, plant, w, eps=None):
    """The number of closed-loop poles in the closed right half plane by the
    Nyquist criterion, on the grid w (rad/s) and an indentation of radius
    eps = w[0] around s = 0 (to the right). Returns (count, ok), ok false when
    the grid is too coarse to unwrap the phase reliably."""
    eps = w[0] if eps is None else eps
    phi = np.linspace(-np.pi / 2, np.pi / 2, 181)
    s_semi = eps * np.exp(1j * phi)
    f_semi = 1.0 + c_fn(s_semi) * plant.g(s_semi)
    s_up = 1j * w
    f_up = 1.0 + c_fn(s_up) * plant.g(s_up)
    a_semi = np.unwrap(np.angle(f_semi))
    a_up = np.unwrap(np.angle(f_up))
    d_up = np.diff(np.angle(f_up))
    d_up = (d_up + np.pi) % (2 * np.pi) - np.pi
    ok = np.max(np.abs(d_up)) < 0.75 * np.pi and np.max(np.abs(np.diff(a_semi))) < 0.75 * np.pi
    # From j w_max to j inf: 1 + L -> 1 (|L| small there, checked).
    lw = np.abs(f_up[-1] - 1.0)
    ok = ok and lw < 0.5
    delta_upper = (a_up[-1] - a_up[0]) + (0.0 - np.angle(f_up[-1]))
    # Semicircle ends at s = j eps, where the upper axis starts: phases agree
    # mod 2 pi; use the semicircle's own change.
    total = (a_semi[-1] - a_semi[0]) + 2.0 * delta_upper
    z = -total / (2.0 * np.pi)
    return int(round(z)), ok and abs(z - round(z)) < 0.05


def peaks_on_grid(g, plant, w):
    s = 1j * w
    c = c_of_gains(g, s)
    l = c * plant.g(s)
    sens = 1.0 / (1.0 + l)
    return np.abs(sens), np.abs(l * sens), np.abs(c * sens)


def refine_peak(fn, w, vals):
    """The largest value of fn (of one w > 0) near the grid's local maxima."""
    best = float(np.max(vals))
    best_w = float(w[int(np.argmax(vals))])
    n = len(w)
    cand = [i for i in range(n) if (i == 0 or vals[i] >= vals[i - 1]) and (i == n - 1 or vals[i] >= vals[i + 1])]
    cand = [i for i in cand if vals[i] >= 0.97 * best]
    for i in cand:
        lo = math.log(w[max(i - 1, 0)])
        hi = math.log(w[min(i + 1, n - 1)])
        if hi <= lo:
            continue
        r = optimize.minimize_scalar(lambda lw: -fn(math.exp(lw)), bounds=(lo, hi), method="bounded",
                                     options=dict(xatol=1e-10 * max(1.0, abs(lo))))
        if -r.fun > best:
            best, best_w = -r.fun, math.exp(r.x)
    return best, best_w


# --------------------------------------------------------------------------
# The analysis of one design (used on pidlab's gains and on the optimum).


class Problem:
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
        self.grid = freq_grid(plant, self.noise, self.w_ref)
        self.dense = freq_grid(plant, self.noise, self.w_ref, n_log=8000, lin_per_ripple=200, max_lin=80000)
        self._windows = {}
        self.evaluations = 0

    # -- the load response ---------------------------------------------
    def window(self, T, n):
        key = (round(math.log(T), 9), n)
        if key not in self._windows:
            if len(self._windows) > 6:
                self._windows.clear()
            self._windows[key] = Window(self.plant, T, n)
        return self._windows[key]

    def fit_window(self, g, T=None, n=1 << 15, rel=1e-7):
        """A window (T, n) that holds the response of g: the tail beyond T
        at most rel of the IAE and T at most 2.2 x the settling time (for
        the resolution)."""
        if T is None:
            fast, slow = self.plant.time_scales()
            T = 60.0 * (self.plant.delay + 2.0 / self.w_ref) + 0.0
        for _ in range(40):
            win = self.window(T, n)
            iae, y = win.iae_of_gains(g)
            if not np.all(np.isfinite(y)):
                return None
            ts = settle_time(y, win.h, iae, rel)
            if ts > 0.55 * T:
                T *= 2.0
                continue
            if ts < 0.2 * T and T > 1e-6:
                T = max(ts / 0.45, 1e-9)
                continue
            return T, n
        return T, n

    def iae(self, g, T=None, check=True):
        """The load IAE of g, on a fitted window, converged in T and n:
        (iae, info)."""
        fit = self.fit_window(g, T)
        if fit is None:
            return math.inf, {}
        T, n = fit
        iae1, y = self.window(T, n).iae_of_gains(g)
        info = dict(window_s=T, samples=n)
        if check:
            iae2, _ = self.window(2.0 * T, 2 * n).iae_of_gains(g)  # longer, same step
            iae3, _ = self.window(T, 4 * n).iae_of_gains(g)  # finer
            info["change_longer"] = abs(iae2 - iae1) / iae1
            info["change_finer"] = abs(iae3 - iae1) / iae1
            iae1 = iae3
        return iae1, info

    # -- the peaks ------------------------------------------------------
    def peaks(self, g, grid=None):
        w = self.dense if grid is None else grid
        a_s, a_t, a_n = peaks_on_grid(g, self.plant, w)
        p = self.plant

        def s_at(wv):
            l = c_of_gains(g, 1j * wv) * p.g(1j * wv)
            return abs(1.0 / (1.0 + l))

        def t_at(wv):
            l = c_of_gains(g, 1j * wv) * p.g(1j * wv)
            return abs(l / (1.0 + l))

        def n_at(wv):
            c = c_of_gains(g, 1j * wv)
            return abs(c / (1.0 + c * p.g(1j * wv)))

        ms, ws = refine_peak(s_at, w, a_s)
        mt, wt = refine_peak(t_at, w, a_t)
        mn, wn = refine_peak(n_at, w, a_n)
        cinf = c_inf(g)
        if cinf > mn:
            mn, wn = cinf, math.inf
        unstable, ok = winding_unstable(lambda s: c_of_gains(g, s), p, w)
        return dict(ms=ms, ms_rad_s=ws, mt=mt, mt_rad_s=wt, noise_gain=mn, noise_rad_s=wn,
                    unstable_poles=unstable, nyquist_ok=bool(ok), stable=bool(ok and unstable == 0))

    def analyse(self, g):
        out = self.peaks(g)
        out["td"] = g["kd"] / g["kp"] if g["kd"] != 0.0 else 0.0
        out["n"] = out["td"] / g["tf"] if g["kd"] != 0.0 and g["tf"] > 0 else math.inf
        if out["stable"]:
            out["iae"], out["iae_info"] = self.iae(g)
        else:
            out["iae"], out["iae_info"] = math.inf, {}
        return out

    def violation(self, a):
        """The largest relative excess over a bound (<= 0: all met)."""
        v = [a["ms"] / self.ms - 1.0, a["mt"] / self.mt - 1.0, a["noise_gain"] / self.noise - 1.0]
        if not self.pi and a["td"] > 0:
            v += [a["td"] / self.td_max - 1.0, a["n"] / self.n_max - 1.0, self.n_min / a["n"] - 1.0]
        if not a["stable"]:
            v.append(math.inf)
        return max(v)

    # -- the constraint set on a grid ----------------------------------
    def constraints(self, x, w):
        """(values, jacobian) of the peak constraints at the grid w, every one
        >= 0 when met: log bound - log |.|, and the high-frequency |C|."""
        s = 1j * w
        c, dc = c_and_grad(x, s, self.pi)
        p = self.plant.g(s)
        l = c * p
        f = 1.0 + l
        dl = dc * p[None, :]
        dlogf = np.real(dl / f[None, :])  # d log|1+L|
        dlogl = np.real(dc / c[None, :])  # d log|L| = d log|C|
        vals = [math.log(self.ms) + np.log(np.abs(f)),
                math.log(self.mt) - np.log(np.abs(l)) + np.log(np.abs(f))]
        jac = [dlogf.T, (dlogf - dlogl).T]
        if np.isfinite(self.noise):
            vals.append(math.log(self.noise) - np.log(np.abs(c)) + np.log(np.abs(f)))
            jac.append((dlogf - dlogl).T)
            # |C(j inf)| = kp (1 + N) (PID), kp (PI).
            if self.pi:
                vals.append(np.array([math.log(self.noise) - x[0]]))
                jac.append(np.array([[-1.0, 0.0]]))
            else:
                nn = math.exp(x[3])
                vals.append(np.array([math.log(self.noise) - x[0] - math.log1p(nn)]))
                jac.append(np.array([[-1.0, 0.0, 0.0, -nn / (1.0 + nn)]]))
        return np.concatenate(vals), np.vstack(jac)

    def stable_x(self, x, w):
        g = gains_of(x, self.pi)
        unstable, ok = winding_unstable(lambda s: c_of_gains(g, s), self.plant, w)
        return ok and unstable == 0

    def bounds(self):
        if self.pi:
            return [(-30.0, 30.0), (-30.0, 30.0)]
        return [(-30.0, 30.0), (-30.0, 30.0), (math.log(self.td_max) - 9.0, math.log(self.td_max)),
                (math.log(self.n_min), math.log(self.n_max))]

    # -- starts -------------------------------------------------------
    def fopdt(self):
        """(K, T, L) of a first-order-plus-dead-time model by the method of
        moments/areas (Astrom & Hagglund): Tar = A0/K, T = e A1/K."""
        p = self.plant
        K = p.static_gain()
        num_asc = p.num[::-1]
        den_asc = p.den[::-1]
        tar = p.delay + den_asc[1] / den_asc[0] - (num_asc[1] / num_asc[0] if len(num_asc) > 1 else 0.0)
        sys_ = signal.lti(p.num, p.den)
        t = np.linspace(0.0, max(tar - p.delay, 1e-9), 4001)
        _, ystep = signal.step(sys_, T=t)
        # A1 = int_0^Tar y(t) dt, the delayed step response.
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
            L = p.delay + lag  # e^(-sL)/(s(1+T1 s)) ~ e^(-s(L+T1))/s
            L = max(L, 1e-3)
            kp = 0.45 / (kv * L)
            ti = 8.0 * L
            td = 0.5 * L
            return kp, kp / ti, td
        K, T, L = self.fopdt()
        kp = (0.2 + 0.45 * T / L) / K
        ti = (0.4 * L + 0.8 * T) / (L + 0.1 * T) * L
        td = 0.5 * L * T / (0.3 * L + T)
        return kp, kp / ti, td

    def feasible_on(self, x, w):
        vals, _ = self.constraints(x, w)
        return np.min(vals) >= 0.0 and self.stable_x(x, w)

    def scale_to_bounds(self, x):
        """Shift log kp and log ki together (Td, N kept) to the largest gain
        that meets the constraints on the grid and is stable."""
        x = np.array(x, float)

        def ok(a):
            y = x.copy()
            y[0] += a
            y[1] += a
            return self.feasible_on(y, self.grid)

        lo, hi = -30.0, 0.0
        if ok(0.0):
            lo = 0.0
            hi = 0.5
            while ok(hi) and hi < 30:
                lo, hi = hi, hi * 2.0
        else:
            hi = 0.0
            lo = -0.5
            while not ok(lo) and lo > -30:
                hi, lo = lo, lo * 2.0
            if not ok(lo):
                return None
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            if ok(mid):
                lo = mid
            else:
                hi = mid
            if hi - lo < 1e-7:
                break
        y = x.copy()
        y[0] += lo
        y[1] += lo
        return y

    def starts(self):
        kp, ki, td = self.amigo_shape()
        if self.pi:
            shapes = [(kp, ki), (kp, 2.0 * ki), (kp, 0.5 * ki), (kp, 4.0 * ki)]
            xs = [np.log(sh) for sh in shapes]
        else:
            xs = []
            td_a = min(td, self.td_max)
            for tdf, nn, kif in ((1.0, 10.0, 1.0), (0.3, 5.0, 1.5), (3.0, 20.0, 1.0), (1.0, 40.0, 0.5),
                                 (0.1, 3.0, 2.0)):
                tdv = min(td_a * tdf, self.td_max)
                xs.append(np.log([kp, ki * kif, tdv, nn]))
        out = []
        for x in xs:
            y = self.scale_to_bounds(x)
            if y is not None:
                out.append(y)
        return out

    # -- the optimisation -----------------------------------------------
    def solve_from(self, x0, win, w, maxiter=120):
        """SLSQP from x0 with the window win and the constraint grid w.
        Returns the best feasible (on w) stable x seen, and its IAE."""
        best = [None, math.inf]
        cache = {}

        def ev(x):
            key = x.tobytes()
            if key not in cache:
                self.evaluations += 1
                cv, cj = self.constraints(x, w)
                stable = self.stable_x(x, w)
                if stable:
                    iae, grad, _ = win.iae_and_grad(x, self.pi)
                    f, fg = math.log(iae), grad / iae
                else:
                    iae, f, fg = math.inf, 50.0, np.zeros_like(x)
                cache.clear()
                cache[key] = (f, fg, cv, cj, stable, iae)
                if stable and np.min(cv) >= -1e-9 and iae < best[1]:
                    best[0], best[1] = x.copy(), iae
            return cache[key]

        lb = np.array([b[0] for b in self.bounds()])
        ub = np.array([b[1] for b in self.bounds()])
        x0 = np.clip(np.asarray(x0, float), lb, ub)
        ev(x0)
        try:
            optimize.minimize(lambda x: ev(x)[0], x0, jac=lambda x: ev(x)[1], method="SLSQP",
                              bounds=self.bounds(),
                              constraints=[dict(type="ineq", fun=lambda x: ev(x)[2], jac=lambda x: ev(x)[3])],
                              options=dict(maxiter=maxiter, ftol=1e-10))
        except (ValueError, FloatingPointError):
            pass
        return best[0], best[1]

    def optimise(self, extra_starts=(), verbose=False):
        """The reference optimum: dict(gains, iae, analysis, ...)."""
        starts = [np.asarray(x, float) for x in extra_starts] + self.starts()
        if not starts:
            return None
        # The window, from the first start's response.
        results = []
        for x0 in starts:
            g0 = gains_of(x0, self.pi)
            fit = self.fit_window(g0)
            if fit is None:
                continue
            win = self.window(*fit)
            x, v = self.solve_from(x0, win, self.grid)
            if x is None:
                continue
            # Re-fit the window at the optimum and polish once on it.
            fit2 = self.fit_window(gains_of(x, self.pi), fit[0])
            if fit2 is not None and abs(math.log(fit2[0] / fit[0])) > 0.3:
                x2, v2 = self.solve_from(x, self.window(*fit2), self.grid)
                if x2 is not None:
                    x, v = x2, v2
            results.append((v, x))
            if verbose:
                print("  start", np.exp(x0), "->", gains_of(x, self.pi), v, file=sys.stderr)
        if not results:
            return None
        results.sort(key=lambda r: r[0])
        v, x = results[0]
        # Exchange: the refined peaks' frequencies join the grid, and re-solve.
        grid = self.grid
        for _ in range(3):
            g = gains_of(x, self.pi)
            a = self.peaks(g)
            if self.violation(dict(a, td=g["kd"] / g["kp"] if g["kd"] else 0.0,
                                   n=(g["kd"] / g["kp"] / g["tf"]) if g["kd"] else math.inf)) <= 1e-6:
                break
            extra = [a[k] for k in ("ms_rad_s", "mt_rad_s", "noise_rad_s") if np.isfinite(a[k])]
            grid = np.unique(np.concatenate([grid, extra, np.array(extra) * (1 - 1e-4), np.array(extra) * (1 + 1e-4)]))
            fit = self.fit_window(g)
            x2, v2 = self.solve_from(x, self.window(*fit), grid, maxiter=40)
            if x2 is not None:
                x, v = x2, v2
        # Scale back until the refined peaks meet the bounds.
        g = gains_of(x, self.pi)
        a = self.analyse(g)
        f = 1.0
        while self.violation(a) > 1e-6 and f > 0.5:
            f *= 0.999
            gs = dict(g, kp=g["kp"] * f, ki=g["ki"] * f, kd=g["kd"] * f)
            a = self.analyse(gs)
            if self.violation(a) <= 1e-6:
                g = gs
                break
        return dict(gains=g, iae=a["iae"], analysis=a, evaluations=self.evaluations)


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
