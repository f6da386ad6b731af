#!/usr/bin/env bash
# Identifying a P2D with delay from 10^4 samples, in pidlab and in scipy, in
# one run on the same data, and the ratio of their CPU times.
#   * The record: Kp = 1.7, Tp1 = 4.2 s, Tp2 = 1.3 s, Td = 0.63 s (6.3
#     samples), dt = 0.1 s, a step-rich input (tests/python/identify_peer.py),
#     white noise at 30 dB (seeded); written once as a CSV (17 digits).
#   * pidlab: `pidlab identify --csv F --model p2d --json` (16 Sobol' starts,
#     Ceres; the CSV read and the covariance included), its process CPU time
#     (user + system, getrusage of the child), best of REPEATS runs.
#   * scipy: identify_peer.fit, what a scipy user writes: least_squares (trf,
#     3-point differences) on the exact ZOH response (expm, lfilter) from a
#     grid of 9 starts, the best kept; time.process_time, one BLAS thread,
#     best of REPEATS runs.
# Both must reach the same parameters to 1e-6 relative (checked: exit 1
# otherwise). Builds nothing.
#   bench/identify_bench.sh [PIDLAB] [SAMPLES] [REPEATS]   (defaults build/bin/pidlab 10000 3)
set -euo pipefail
pidlab=${1:-}
[ -z "$pidlab" ] || pidlab=$(realpath -m -- "$pidlab")  # relative to where it is run from
cd "$(dirname "$0")/.."
pidlab=${pidlab:-build/bin/pidlab}
samples=${2:-10000}
repeats=${3:-3}
[ -x "$pidlab" ] || { echo "identify_bench.sh: $pidlab is not an executable (build pidlab first)" >&2; exit 2; }
python=/usr/bin/python3  # Debian's, with python3-scipy (scripts/install-deps.sh)
"$python" -c 'import scipy.optimize' 2>/dev/null || { echo "identify_bench.sh: $python has no scipy (apt-get install python3-scipy)" >&2; exit 2; }
OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 "$python" - "$pidlab" "$samples" "$repeats" <<'EOF'
import json, os, resource, subprocess, sys, tempfile, time
import numpy as np
import scipy
sys.path.insert(0, os.path.join(os.getcwd(), "tests", "python"))
import identify_peer as peer

pidlab, samples, repeats = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
dt, truth = 0.1, [1.7, 4.2, 1.3, 0.63]
rng = np.random.default_rng(24)
t = np.arange(samples) * dt
u = peer.step_rich_input(samples, rng)
clean = peer.simulate("p2d", truth, u, dt)
y = clean + rng.normal(0.0, np.std(clean) / np.sqrt(1000.0), samples)
u, y = u + 0.5, y + 2.0

def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime

with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "p2d.csv")
    peer.write_csv(path, t, u, y)
    pidlab_cpu = []
    for _ in range(repeats):
        before = children_cpu()
        # The whole record, however long (--max-samples: not decimated, as scipy fits it).
        out = subprocess.run([pidlab, "identify", "--csv", path, "--model", "p2d", "--json",
                              "--max-samples", str(max(samples, 100))], capture_output=True,
                             text=True, check=True)
        pidlab_cpu.append(children_cpu() - before)
    j = json.loads(out.stdout)
ours = np.array([j["parameters"][name]["value"] for name in peer.NAMES["p2d"]])
scipy_cpu = []
for _ in range(repeats):
    start = time.process_time()
    theirs, cost, result = peer.fit("p2d", t, u, y)
    scipy_cpu.append(time.process_time() - start)
scipy_starts = len(peer.default_starts("p2d"))
worst = float(np.max(np.abs(ours - theirs) / np.abs(theirs)))
agree = worst <= 1e-6
a, b = min(pidlab_cpu), min(scipy_cpu)
print(f"P2D with delay, {samples} samples, dt = {dt} s, 30 dB: CPU time, best of {repeats}")
print(f"{'':8} {'CPU s':>8} {'starts':>7} {'s/start':>8}  {'Kp':>13} {'Tp1':>13} {'Tp2':>13} {'Td':>13}  cost")
print(f"{'pidlab':8} {a:8.3f} {j['starts']:>7} {a / j['starts']:8.3f}  " + " ".join(f"{v:13.9f}" for v in ours) + f"  {j['cost']:.12g}")
print(f"{'scipy':8} {b:8.3f} {scipy_starts:>7} {b / scipy_starts:8.3f}  " + " ".join(f"{v:13.9f}" for v in theirs) + f"  {cost:.12g}")
print(f"ratio scipy / pidlab: {b / a:.2f}x ({(b / scipy_starts) / (a / j['starts']):.2f}x a start); same parameters to 1e-6: {'yes' if agree else 'NO'} "
      f"(worst relative difference {worst:.2g}); scipy {scipy.__version__}, numpy {np.__version__}")
print(f"(pidlab: {j['starts_at_best']} of {j['starts']} starts reached the best cost; scipy: {len(peer.default_starts('p2d'))} starts, "
      f"the best kept; all runs, s: pidlab {', '.join(f'{v:.3f}' for v in pidlab_cpu)}; "
      f"scipy {', '.join(f'{v:.3f}' for v in scipy_cpu)})")
sys.exit(0 if agree else 1)
EOF
