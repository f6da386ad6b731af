#!/usr/bin/env bash
# The design engine against an independent optimum, with its time (issue 57;
# docs/benchmarks.md, "The design engine against an independent optimum"):
# tests/python/design_reference_test.py's 108 cases (43 plants at Ms = Mt <=
# 1.59 and two noise bounds, ten of them as PI too), each `pidlab tune`'s
# load integral |e| dt beside the reference optimum's and the design's wall
# time (`wall_time_s`, one process, one core). Prints a Markdown table of the
# cases at the default noise bound and a summary of all; exit 1 if a case
# fails (a ratio over 1.03, a bound broken, or a refusal).
#   bench/design_bench.sh [BIN_DIR]
set -uo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-build/bin}")
out=$(mktemp)
trap 'rm -f "$out"' EXIT
/usr/bin/python3 tests/python/design_reference_test.py "$bin/pidlab" >"$out"
rc=$?
/usr/bin/python3 - "$out" <<'PY'
import re, statistics, sys
rows, seen, times = [], set(), []
for line in open(sys.argv[1]):
    f = line.split()
    if not line.rstrip().endswith("ok") or line.startswith("FAIL"):
        continue
    # the name (it may hold spaces) in 18 columns, 9 numbers, the verdict
    name = line[:18].strip()
    g, iae_p, iae_r, _, ratio, ms, _, t = (float(x) for x in f[-9:-1])
    times.append(t)
    if name not in seen:  # the first noise bound: the default
        seen.add(name)
        rows.append((name, g, iae_p, iae_r, ratio, ms, t))
print("| plant | noise bound | load ∫\\|e\\|dt | reference optimum | ratio | Ms | design time [s] |")
print("|---|---|---|---|---|---|---|")
for name, g, iae_p, iae_r, ratio, ms, t in rows:
    print("| %s | %.4g | %.6g | %.6g | %.4f | %.4f | %.3f |" % (name, g, iae_p, iae_r, ratio, ms, t))
if times:
    over = sum(1 for t in times if t > 0.5)
    print("\n%d cases: design time median %.3f s, at most %.3f s, %d over 0.5 s"
          % (len(times), statistics.median(times), max(times), over))
PY
tail -2 "$out"
exit $rc
