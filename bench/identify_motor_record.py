#!/usr/bin/python3
"""Writes the motor record of bench/identify_bench.sh: 4 e^(-0.025 s) /
((0.35 s + 1)(0.004 s + 1)) sampled every 2 ms, its input a square wave
between 0 and 1 (at rest for 0.1 s, then 3 s at each level: one step in 1501 samples), its output
quantised as a coarse encoder's (steps of 0.05) and nothing else added. The
second lag, two samples long, hides behind the delay and the quantisation:
P2D's Tp2 is not identifiable.

Usage: identify_motor_record.py SAMPLES OUT.csv
"""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "python"))
import identify_peer as peer  # noqa: E402

DT_S, TRUTH, RESOLUTION = 0.002, [4.0, 0.35, 0.004, 0.025], 0.05
REST_S, HALF_PERIOD_S = 0.1, 3.0


def motor_record(samples):
    t = np.arange(samples) * DT_S
    u = np.where(t < REST_S - 1e-9, 0.0, 1.0 - np.floor((t - REST_S + 1e-9) / HALF_PERIOD_S) % 2)
    y = RESOLUTION * np.round(peer.simulate("p2d", TRUTH, u, DT_S) / RESOLUTION)
    return t, u, y


if __name__ == "__main__":
    peer.write_csv(sys.argv[2], *motor_record(int(sys.argv[1])))
