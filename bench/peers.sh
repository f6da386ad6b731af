#!/usr/bin/env bash
# The paper's objective (IAE, eq. 4: 501 samples of the unit step response of
# the continuous loop, ts = 0.05 s, horizon 25 s) per plant, in pidlab and in
# scipy, in one run on the same machine, and the ratio.
#   * pidlab: objective_bench's BM_PaperObjectiveContinuous (ObjectiveEvaluator,
#     stability test included), CPU time per evaluation.
#   * scipy: what a user writes: the closed loop T = C G / (1 + C G) with the
#     ideal PID C = (kd s^2 + kp s + ki) / s as a transfer function,
#     scipy.signal.step at t = 0, 0.05, ..., 25, IAE = sum |1 - y|; CPU time
#     per evaluation (time.process_time over repeated calls, one BLAS thread).
# Same plants, coefficients and gains (the paper's Nelder-Mead gains), read
# from objective_bench's JSON context; both IAEs must agree to 1e-6 relative
# (checked: exit 1 otherwise). Builds nothing.
#   bench/peers.sh [OBJECTIVE_BENCH]        (default build/bin/objective_bench)
set -euo pipefail
cd "$(dirname "$0")/.."
bench=${1:-build/bin/objective_bench}
[ -x "$bench" ] || { echo "peers.sh: $bench is not an executable (build objective_bench first)" >&2; exit 2; }
python=/usr/bin/python3  # Debian's, with python3-scipy (scripts/install-deps.sh)
"$python" -c 'import scipy.signal' 2>/dev/null || { echo "peers.sh: $python has no scipy (apt-get install python3-scipy)" >&2; exit 2; }
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
echo "objective_bench ..." >&2
"$bench" --benchmark_filter='BM_PaperObjectiveContinuous' --benchmark_min_time=1 --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_format=json > "$tmp"
echo "scipy ..." >&2
OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 "$python" - "$tmp" <<'EOF'
import json, sys, time
import numpy as np
from scipy import signal

report = json.load(open(sys.argv[1]))
context = report["context"]
pidlab = {}
for b in report["benchmarks"]:
    if b.get("aggregate_name") != "median":
        continue
    plant, iae = b["label"].split(" iae=")
    unit = {"ns": 1e-3, "us": 1.0, "ms": 1e3}[b["time_unit"]]
    pidlab[plant] = (b["cpu_time"] * unit, float(iae))

t = np.arange(501) * 0.05

def scipy_iae(num, den, kp, ki, kd):
    pid_num, pid_den = [kd, kp, ki], [1.0, 0.0]
    loop_num = np.polymul(pid_num, num)
    loop_den = np.polyadd(np.polymul(pid_den, den), loop_num)
    _, y = signal.step((loop_num, loop_den), T=t)
    return float(np.sum(np.abs(1.0 - y)))

def cpu_us(f, min_s=1.0):
    n, start = 0, time.process_time()
    while True:
        f()
        n += 1
        elapsed = time.process_time() - start
        if elapsed >= min_s:
            return 1e6 * elapsed / n

ok = True
print(f"{'plant':<18} {'pidlab us':>10} {'scipy us':>10} {'ratio':>8}  {'pidlab IAE':>18} {'scipy IAE':>18}  agree")
for key, value in sorted(context.items()):
    if not key.startswith("plant."):
        continue
    plant = key[len("plant."):]
    fields = dict(part.split("=") for part in value.split(";"))
    num = [float(v) for v in fields["num"].split(",")]
    den = [float(v) for v in fields["den"].split(",")]
    kp, ki, kd = (float(v) for v in fields["gains"].split(","))
    iae = scipy_iae(num, den, kp, ki, kd)
    best = min(cpu_us(lambda: scipy_iae(num, den, kp, ki, kd)) for _ in range(3))
    ours, our_iae = pidlab[plant]
    agree = abs(iae - our_iae) <= 1e-6 * max(1.0, abs(our_iae))
    ok = ok and agree
    print(f"{plant:<18} {ours:>10.2f} {best:>10.1f} {best / ours:>7.0f}x  {our_iae:>18.10f} {iae:>18.10f}  {'yes' if agree else 'NO'}")
print(f"(pidlab: median CPU time of 3 repetitions; scipy {__import__('scipy').__version__}: best of 3 CPU-time means)")
sys.exit(0 if ok else 1)
EOF
