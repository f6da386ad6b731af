#!/usr/bin/env bash
# Every tuning method of pidlab over seeds 1-20 on the three plants (paper's
# objective, Ceres cross-check on): the lowest and highest objective per
# method, the best any seed and method finds, and whether the default
# (multi-start) reaches it to 0.1 % for every seed. Prints a Markdown table
# (docs/tuning.md, "A search that does not depend on luck").
#   bench/tune_seeds.sh [BIN_DIR] [LAST_SEED]     (default build/bin 20; a few minutes)
set -euo pipefail
bin=${1:-build/bin}
last=${2:-20}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
for plant in double_integrator oscillator stepper_motor; do
  for method in multi-start nelder-mead paper-nm ga pso-gsa; do
    for seed in $(seq 1 "$last"); do
      "$bin/pidlab" tune --plant "$plant" --method "$method" --seed "$seed" --json |
        python3 -c "import json, sys; j = json.load(sys.stdin); print('$plant', '$method', $seed, repr(j['objective']), j['wall_time_s'])"
    done
    echo "  $plant $method done" >&2
  done
done > "$tmp/all.txt"
python3 - "$tmp/all.txt" "$last" <<'PY'
import sys, collections
rows = [l.split() for l in open(sys.argv[1])]
last = sys.argv[2]
by = collections.defaultdict(list)
for plant, method, seed, f, t in rows:
    by[(plant, method)].append((float(f), int(seed)))
print(f"| plant | method | lowest (seed) | highest (seed) | seeds within 0.1 % of the best of all |")
print("|---|---|---|---|---|")
for plant in ["double_integrator", "oscillator", "stepper_motor"]:
    best = min(f for (p, m), v in by.items() if p == plant for f, s in v)
    for method in ["multi-start", "nelder-mead", "paper-nm", "ga", "pso-gsa"]:
        v = by[(plant, method)]
        lo, hi = min(v), max(v)
        ok = sum(f <= best * 1.001 for f, s in v)
        print(f"| {plant} | {method} | {lo[0]:.6f} ({lo[1]}) | {hi[0]:.6f} ({hi[1]}) | {ok}/{len(v)} |")
    print(f"| {plant} | **best of all** | **{best:.6f}** | | |")
PY
