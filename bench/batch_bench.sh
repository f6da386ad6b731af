#!/usr/bin/env bash
# The whole AMIGO test batch's wall time (docs/benchmarks.md, "The AMIGO test
# batch"): `pidlab batch --set amigo --json` with --jobs 1 and with every core
# (--jobs 0), in one run; prints both times in seconds and their ratio, and
# checks that the two runs give the same numbers (the result does not depend
# on the number of jobs).
#   bench/batch_bench.sh [BIN_DIR] [EXTRA FLAGS, e.g. --families P1,P4]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-build/bin}")
shift || true
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
run() {  # jobs, output file -> wall seconds
  local start end
  start=$(date +%s.%N)
  "$bin/pidlab" batch --set amigo --json --jobs "$1" "${@:3}" > "$2"
  end=$(date +%s.%N)
  python3 -c "print(f'{$end - $start:.1f}')"
}
one=$(run 1 "$tmp/one.json" "$@")
all=$(run 0 "$tmp/all.json" "$@")
python3 - "$tmp/one.json" "$tmp/all.json" "$one" "$all" <<'PY'
import json, os, sys
one, every = (json.load(open(f)) for f in sys.argv[1:3])
t1, tn = float(sys.argv[3]), float(sys.argv[4])
strip = lambda j: [{k: v for k, v in p.items() if k != 'wall_time_s'} for p in j['plants']]
same = strip(one) == strip(every)
s = every['summary']
print(f"plants {s['plants']}, cores {os.cpu_count()} (jobs {every['jobs']})")
print(f"--jobs 1: {t1:.1f} s   --jobs {every['jobs']}: {tn:.1f} s   ratio {t1 / tn:.2f}x")
print(f"same numbers with 1 and {every['jobs']} jobs: {same}")
print(f"AMIGO feasible {s['amigo_feasible']}, pidlab wins {s['wins']}, ties {s['ties']}, loses {s['losses']}")
sys.exit(0 if same else 1)
PY
