#!/usr/bin/python3
"""An independent reference for pidlab's continuous loop with dead time.

The loop of docs/deadtime.md ("The continuous loop"): plant G(s) e^(-sL) with
the disturbance n added to the plant input before the delay,
    x' = A x + B p(t),  p(t) = u(t - L) + n(t - L)  (0 for t < L),  y = C x,
the PID on e = r - y (PI, filtered PID kd s / (tf s + 1), or the ideal PID on
a plant of relative degree >= 2, whose step kick kd r delta(t) reaches the
plant at t = L: x jumps by kd r B there).

Integrated by the method of steps with scipy's solve_ivp (DOP853, rtol 1e-12,
dense output), interval by interval, breaking at every disturbance edge and
every multiple of L after it (and of L after 0): on each interval the delayed
input is read from the dense outputs of earlier intervals. No code is shared
with pidlab's C++ path (which uses matrix exponentials and a Hermite store).

Usage: dde_reference.py --num 1 --den 1,1 --delay 0.3 --gains 1,1,0 [--tf 0]
    [--square AMP,PERIOD] [--ts 0.05] [--horizon 25] [--reference 1]
prints JSON {"y": [...], "iae": ..., "itae": ..., "load_iae": ...}.
"""

import argparse
import bisect
import json
import math
import sys

import numpy as np
from scipy.integrate import solve_ivp


def realise(num, den):
    """Controllable canonical form of num/den (strictly proper)."""
    den = np.trim_zeros(np.asarray(den, float), "f")
    num = np.trim_zeros(np.asarray(num, float), "f")
    a0 = den[0]
    den = den / a0
    num = num / a0
    n = len(den) - 1
    a = np.zeros((n, n))
    a[:-1, 1:] = np.eye(n - 1)
    a[-1, :] = -den[::-1][:-1]
    b = np.zeros(n)
    b[-1] = 1.0
    c = np.zeros(n)
    padded = np.concatenate([np.zeros(n - len(num)), num])
    c[:] = padded[::-1]
    return a, b, c


class Square:
    """+amp on [0, P/2), -amp on [P/2, P), ... (0 before t = 0)."""

    def __init__(self, amp, period):
        self.amp, self.half = amp, period / 2.0

    def __call__(self, t):
        if t < 0.0:
            return 0.0
        k = math.floor(t / self.half + 1e-12)
        return self.amp if k % 2 == 0 else -self.amp

    def edges(self, horizon):
        k = 1
        out = []
        while k * self.half <= horizon:
            out.append(k * self.half)
            k += 1
        return out


class Step:
    def __init__(self, amp):
        self.amp = amp

    def __call__(self, t):
        return self.amp if t >= 0.0 else 0.0

    def edges(self, horizon):
        return []


class Zero:
    def __call__(self, t):
        return 0.0

    def edges(self, horizon):
        return []


class Loop:
    def __init__(self, num, den, gains, tf, delay, n, r):
        self.a, self.b, self.c = realise(num, den)
        self.kp, self.ki, self.kd = gains
        self.tf, self.delay, self.n, self.r = tf, delay, n, r
        self.order = len(self.b)
        self.ideal = self.kd > 0.0 and tf == 0.0
        if self.ideal and abs(self.c @ self.b) > 0.0:
            raise SystemExit("ideal derivative on relative degree 1: neutral loop")
        self.segments = []  # (t0, t1, dense solution)
        self.source = None
        self.starts = []

    def control(self, s, state):
        """u(s) from the loop's state [x, z, v] at time s >= 0."""
        x, z = state[: self.order], state[self.order]
        e = self.r - self.c @ x
        u = self.kp * e + self.ki * z
        if self.kd > 0.0 and self.tf > 0.0:
            v = state[self.order + 1]
            u += self.kd / self.tf * (e - v)
        elif self.ideal:
            u += -self.kd * (self.c @ (self.a @ x))  # kd e' with C B = 0
        return u

    def state_at(self, s):
        i = bisect.bisect_right(self.starts, s) - 1
        t0, t1, sol = self.segments[i]
        return sol(min(max(s, t0), t1))

    def plant_input(self, t):
        # The interval's delayed range lies in one earlier segment (its
        # breaks include every break + L): read that one, so that both ends
        # of the interval see its one-sided limits.
        if self.source is None:
            return 0.0
        t0, t1, sol = self.segments[self.source]
        s = min(max(t - self.delay, t0), t1)
        n = self.n(s) if s < t1 else self.n_left(t1)
        return self.control(s, sol(s)) + n

    def rhs(self, t, w):
        x = w[: self.order]
        e = self.r - self.c @ x
        dx = self.a @ x + self.b * self.plant_input(t)
        out = [dx, [e]]
        if self.kd > 0.0 and self.tf > 0.0:
            out.append([(e - w[self.order + 1]) / self.tf])
        return np.concatenate(out)

    def run(self, horizon):
        breaks = set()
        for origin in [0.0] + self.n.edges(horizon):
            k = 0
            while origin + k * self.delay <= horizon + 1e-12:
                breaks.add(round(origin + k * self.delay, 12))
                k += 1
        breaks = sorted(b for b in breaks if b > 0.0) + [horizon]
        size = self.order + 1 + (1 if self.kd > 0.0 and self.tf > 0.0 else 0)
        w = np.zeros(size)
        t = 0.0
        for tb in breaks:
            if tb <= t + 1e-14:
                continue
            if self.ideal and abs(t - self.delay) < 1e-12:
                w[: self.order] += self.kd * self.r * self.b
            s0 = t - self.delay
            self.source = None if s0 < -1e-12 else max(0, bisect.bisect_right(self.starts, s0 + 1e-12) - 1)
            sol = solve_ivp(self.rhs, (t, tb), w, method="DOP853", rtol=1e-12, atol=1e-15, dense_output=True)
            if not sol.success:
                raise SystemExit(sol.message)
            self.segments.append((t, tb, sol.sol))
            self.starts.append(t)
            w = sol.y[:, -1]
            t = tb

    def n_left(self, t):
        return self.n(t - 1e-9)

    def output(self, t):
        return float(self.c @ self.state_at(t)[: self.order])


def simulate(args, n, r):
    num = [float(v) for v in args.num.split(",")]
    den = [float(v) for v in args.den.split(",")]
    gains = [float(v) for v in args.gains.split(",")]
    loop = Loop(num, den, gains, args.tf, args.delay, n, r)
    loop.run(args.horizon)
    count = int(round(args.horizon / args.ts)) + 1
    return [loop.output(k * args.ts) for k in range(count)]


def reference(argv=None):
    """The reference's result for these arguments (sys.argv[1:] by default),
    as the object main() prints."""
    p = argparse.ArgumentParser()
    p.add_argument("--num", required=True)
    p.add_argument("--den", required=True)
    p.add_argument("--delay", type=float, required=True)
    p.add_argument("--gains", required=True)
    p.add_argument("--tf", type=float, default=0.0)
    p.add_argument("--square", default="")
    p.add_argument("--ts", type=float, default=0.05)
    p.add_argument("--horizon", type=float, default=25.0)
    p.add_argument("--reference", type=float, default=1.0)
    args = p.parse_args(argv)
    n = Zero()
    if args.square:
        amp, period = (float(v) for v in args.square.split(","))
        n = Square(amp, period)
    r = args.reference
    y = simulate(args, n, r)
    e = [abs(r - v) for v in y]
    load = simulate(args, Step(1.0), 0.0)
    out = {
        "y": y,
        "iae": sum(e),
        "itae": sum(k * args.ts * v for k, v in enumerate(e)),
        "load_iae": sum(abs(v) for v in load),
    }
    return out


def main():
    json.dump(reference(), sys.stdout)


if __name__ == "__main__":
    main()
