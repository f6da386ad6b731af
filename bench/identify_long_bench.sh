#!/usr/bin/env bash
# A record beyond --max-samples (docs/identify.md, "Long records"): the wall
# and CPU time of `pidlab identify --model MODEL` on a ROWS-row CSV of a P1D
# step with delay (Kp = 2, Tp1 = 40 s, Td = 5 s, dt = 0.01 s, noise 0.02,
# seeded; the record of tests/cli/identify_long_cli_test.sh), at each limit
# of LIMITS: the decimation factor, the samples fitted, Kp, Tp1, Td. What the
# default limit (10000) was chosen from. Builds nothing.
#   bench/identify_long_bench.sh [PIDLAB] [ROWS] [MODEL] [LIMITS]
#   (defaults build/bin/pidlab 200000 p1d "2500 5000 10000 20000 40000")
set -euo pipefail
pidlab=${1:-}
[ -z "$pidlab" ] || pidlab=$(realpath -m -- "$pidlab")
cd "$(dirname "$0")/.."
pidlab=${pidlab:-build/bin/pidlab}
rows=${2:-200000} model=${3:-p1d} limits=${4:-"2500 5000 10000 20000 40000"}
[ -x "$pidlab" ] || { echo "identify_long_bench.sh: $pidlab is not an executable (build pidlab first)" >&2; exit 2; }
/usr/bin/python3 - "$pidlab" "$rows" "$model" $limits <<'EOF_PY'
import json, math, os, random, resource, subprocess, sys, tempfile, time
pidlab, rows, model, limits = sys.argv[1], int(sys.argv[2]), sys.argv[3], [int(v) for v in sys.argv[4:]]
rng, kp, tau, td, dt = random.Random(59), 2.0, 40.0, 5.0, 0.01
with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, 'long.csv')
    a, y = math.exp(-dt / tau), 0.0
    with open(path, 'w') as f:
        f.write('t,u,y\n')
        for k in range(rows):
            t = k * dt
            f.write('%.2f,%g,%.6f\n' % (t, 1.0 if t >= 100.0 else 0.0, y + rng.gauss(0.0, 0.02)))
            y = a * y + kp * (1.0 - a) * (1.0 if t - td >= 100.0 - 1e-9 else 0.0)
    print(f'{model} on {rows} rows, load average {os.getloadavg()[0]:.1f}, {os.cpu_count()} cores')
    print(f"{'limit':>7} {'factor':>6} {'fitted':>7} {'wall s':>7} {'CPU s':>7}  {'Kp':>9} {'Tp1':>9} {'Td':>9}")
    for limit in limits:
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        before, start = r.ru_utime + r.ru_stime, time.monotonic()
        out = subprocess.run([pidlab, 'identify', '--csv', path, '--model', model, '--u0', '0', '--json', '--quiet',
                              '--max-samples', str(limit)], capture_output=True, text=True, check=True)
        wall = time.monotonic() - start
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        j = json.loads(out.stdout)
        p = {k: v['value'] for k, v in j['parameters'].items()}
        print(f"{limit:>7} {j['decimation']['factor']:>6} {j['samples']:>7} {wall:7.2f} {r.ru_utime + r.ru_stime - before:7.2f}  "
              f"{p['Kp']:9.5f} {p.get('Tp1', float('nan')):9.4f} {p['Td']:9.4f}")
EOF_PY
