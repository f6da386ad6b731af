#!/usr/bin/env bash
# pidlab plot from evaluations: a PNG of the requested size whose data files
# hold the trajectory `pidlab evaluate --trajectory-csv` prints; the
# continuous loop is drawn at the sample times; bad input exits 2.
# Usage: plot_cli_test.sh PIDLAB_BINARY
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
pidlab=$(realpath -- "${1:?usage: plot_cli_test.sh PIDLAB_BINARY}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
failed=0
pass() { echo "PASS $1"; }
fail() { echo "FAIL $1"; failed=1; }

loop=(--plant double_integrator --loop sampled --dt 0.002 --horizon 4 --disturbance-amplitude 0.1)
"$pidlab" evaluate "${loop[@]}" --gains 1,0.5,2 --trajectory-csv a.csv >/dev/null || fail "evaluate a"
"$pidlab" evaluate "${loop[@]}" --gains 3,1,2 --trajectory-csv b.csv >/dev/null || fail "evaluate b"
if "$pidlab" plot "${loop[@]}" --gains 1,0.5,2 --gains 3,1,2 --out out --width 1000 --height 640 >plot.out &&
   python3 - out/evaluation.png out/evaluation_data a.csv b.csv <<'PY'
import csv, struct, sys
png, data, a, b = sys.argv[1:5]
head = open(png, "rb").read(24)
assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", "not a PNG"
assert struct.unpack(">II", head[16:24]) == (1000, 640), struct.unpack(">II", head[16:24])
def series(name):
    return [tuple(map(float, l.split())) for l in open(f"{data}/{name}.dat") if l.strip() and not l.startswith("#")]
for i, path in enumerate((a, b)):
    traj = list(csv.DictReader(open(path)))
    y = series(f"p0_s{i + 1}")  # s0 is the reference
    u = series(f"p2_s{i}")
    n = series(f"p3_s{i}")
    assert len(y) == len(traj) == len(u) == len(n), (len(y), len(traj))
    for k, row in enumerate(traj):
        assert y[k] == (float(row["t"]), float(row["y"])), (k, y[k], row)
        assert u[k][1] == float(row["u"]) and n[k][1] == float(row["n"]), k
print("both gain sets match their trajectories")
PY
then
  pass "plot overlays two gain sets: PNG 1000x640, data = evaluate's trajectories"
else
  fail "plot of the sampled loop"
fi

if "$pidlab" plot --plant oscillator --gains 2,1,1 --horizon 25 --sample-time 0.1 --out cont >/dev/null &&
   "$pidlab" evaluate --plant oscillator --gains 2,1,1 --horizon 25 --sample-time 0.1 --samples-csv cont.csv >/dev/null &&
   grep -q "y, e, n and u at the sample times" cont/evaluation_data/figure.gp && python3 - cont <<'PY'
import csv, sys
rows = list(csv.DictReader(open("cont.csv")))
u = [tuple(map(float, l.split())) for l in open(sys.argv[1] + "/evaluation_data/p2_s0.dat") if l.strip() and not l.startswith("#")]
assert len(u) == len(rows), (len(u), len(rows))
for k, row in enumerate(rows):
    assert u[k] == (float(row["t"]), float(row["u"])), (k, u[k], row["u"])
PY
then
  pass "continuous loop: y, e, n and u at the sample times (u that of evaluate --samples-csv), said in the title"
else
  fail "plot of the continuous loop"
fi

for args in "--plant nope --gains 1,1,1 --out x" "--plant oscillator --gains 1,1 --out x" \
            "--plant oscillator --out x" "--log missing.lcmlog --out x" "--plant oscillator --gains 1,1,1 --out x --width 5"; do
  status=0
  # shellcheck disable=SC2086
  "$pidlab" plot $args >bad.out 2>bad.err || status=$?
  if [[ $status -eq 2 ]] && only_line_ok bad.err "error:"; then pass "bad input '$args' exits 2 with one line"
  else fail "bad input '$args': status $status, $(cat bad.err)"; fi
done
exit $failed
