#!/usr/bin/env bash
# Whole or nothing on a full disk (docs/security.md): a small tmpfs, mounted
# in a private mount namespace this script makes (unshare -m), holds an old
# version of every output, and is then filled. export, identify --out,
# evaluate --samples-csv and --trajectory-csv, plot --out and report each
# must exit 1 with one line naming "No space left on device" and the path,
# and leave the folder exactly as it was: the old files, byte for byte, and
# no temporary. Then export's directory-in-the-way and read-only-old-file
# cases, plot over a read-only old PNG and report over a read-only old
# report.md (exit 2, one line, at once): non-zero, nothing written.
# usage: full_disk_test.sh PIDLAB_BINARY
set -uo pipefail
pidlab=$(realpath -- "${1:?usage: full_disk_test.sh PIDLAB_BINARY}")
if [ "${PIDLAB_IN_MOUNT_NS:-}" != 1 ]; then
  exec env PIDLAB_IN_MOUNT_NS=1 unshare -m --propagation private bash "$0" "$@"
fi
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule
work=$(mktemp -d)
trap 'umount "$work/full" 2>/dev/null; rm -rf "$work"' EXIT
cd "$work" || exit 1
passed=0 failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

# A record to identify, on the ordinary disk.
/usr/bin/python3 - <<'PY'
import math
with open("step.csv", "w") as f:
    f.write("t,u,y\n")
    for k in range(200):
        t = 0.1 * k
        u, y = (1, 2 * (1 - math.exp(-(t - 0.5) / 3))) if t >= 0.5 else (0, 0.0)
        f.write(f"{t:.1f},{u},{y:.9f}\n")
PY
"$pidlab" launch --help >/dev/null 2>&1 || true

mkdir full
mount -t tmpfs -o size=256k,mode=0755 tmpfs full || { echo "FAIL: cannot mount a tmpfs (root is needed)"; exit 1; }
mkdir -p full/export full/report full/plot/evaluation_data
for f in export/pidlab_pid.h export/pidlab_pid.c model.json samples.csv trajectory.csv replay.csv report/report.md \
         plot/evaluation.png plot/evaluation_data/p0_s0.dat; do
  echo "old $f" > "full/$f"
done
snapshot() { (cd full && find . -path ./filler -prune -o -print0 | sort -z | xargs -0 ls -ld --time-style=+ | awk '{$6=""; print}'; find . -type f ! -name filler -print0 | sort -z | xargs -0 sha256sum); }
# Filled to the last page: every later write of data fails with ENOSPC.
dd if=/dev/zero of=full/filler bs=4096 2>/dev/null
dd if=/dev/zero of=full/filler2 bs=1 count=4096 2>/dev/null
before=$(snapshot)

expect_full() {  # expect_full NAME PATH_IN_MESSAGE COMMAND...
  local name=$1 path=$2; shift 2
  local rc=0
  "$@" >out 2>err || rc=$?
  local after
  after=$(snapshot)
  if [ "$rc" -ne 1 ]; then
    fail "$name: exit $rc (1 expected): $(head -c 300 err)"
  elif ! why=$(only_line_ok err "No space left on device"); then
    fail "$name: $why"
  elif ! grep -qF "$path" err; then
    fail "$name: the line names not both the cause and $path: $(cat err)"
  elif [ "$after" != "$before" ]; then
    fail "$name: the folder changed: $(diff <(echo "$before") <(echo "$after") | head -5)"
  else
    pass "$name: exit 1, '$(cut -c1-150 err)', the folder as it was"
  fi
}

expect_full "export" "full/export/pidlab_pid" \
  "$pidlab" export --gains 2,1,0.5 --dt 0.001 --lang c --out full/export
expect_full "identify --out" "full/model.json" \
  "$pidlab" identify --csv step.csv --model p1d --out full/model.json
expect_full "evaluate --samples-csv" "full/samples.csv" \
  "$pidlab" evaluate --plant double_integrator --gains 3.9,0.06,4.9 --samples-csv full/samples.csv
expect_full "evaluate --trajectory-csv" "full/trajectory.csv" \
  "$pidlab" evaluate --plant double_integrator --gains 3.9,0.06,4.9 --loop sampled --trajectory-csv full/trajectory.csv
expect_full "plot --out" "full/plot" \
  "$pidlab" plot --plant double_integrator --gains 3.9,0.06,4.9 --out full/plot
expect_full "report" "full/report" \
  "$pidlab" report --quick --out full/report

# The same outputs on a disk with room: written, the old content replaced.
umount full
mount -t tmpfs -o size=4m,mode=0755 tmpfs full
mkdir -p full/export
if "$pidlab" export --gains 2,1,0.5 --dt 0.001 --lang c --out full/export >out 2>err &&
   grep -q "pidlab_pid_step" full/export/pidlab_pid.c && [ "$(ls -A full/export | wc -l)" -eq 2 ]; then
  pass "export with room: both files, nothing else"
else
  fail "export with room: $(cat err) $(ls -A full/export)"
fi

# A directory where pidlab_pid.c should be, and a read-only old header:
# non-zero, nothing written.
mkdir -p dir_in_way/pidlab_pid.c
rc=0; "$pidlab" export --gains 2,1,0.5 --dt 0.001 --lang c --out dir_in_way >out 2>err || rc=$?
if [ "$rc" -ne 0 ] && [ ! -e dir_in_way/pidlab_pid.h ] && only_line_ok err "is a directory" >/dev/null; then
  pass "export with a directory in the way: exit $rc, '$(cat err)', no header written"
else
  fail "export with a directory in the way: exit $rc, $(cat err), $(ls -A dir_in_way)"
fi
mkdir -p read_only && echo "old header" > read_only/pidlab_pid.h && chmod 0444 read_only/pidlab_pid.h
rc=0; "$pidlab" export --gains 2,1,0.5 --dt 0.001 --lang c --out read_only >out 2>err || rc=$?
if [ "$rc" -ne 0 ] && [ ! -e read_only/pidlab_pid.c ] && [ "$(cat read_only/pidlab_pid.h)" = "old header" ] &&
   only_line_ok err "read-only" >/dev/null; then
  pass "export over a read-only old header: exit $rc, '$(cat err)', nothing written"
else
  fail "export over a read-only old header: exit $rc, $(cat err), $(ls -A read_only)"
fi

# plot over a read-only old PNG: refused before any work (exit 2, one line),
# the folder exactly as it was (no data files, no stage).
mkdir -p plot_ro && echo "old png" > plot_ro/evaluation.png && chmod 0444 plot_ro/evaluation.png
ro_before=$(cd plot_ro && find . -print0 | sort -z | xargs -0 ls -ld --time-style=+ | awk '{$6=""; print}' | grep -v ' \.$')
rc=0; "$pidlab" plot --plant double_integrator --gains 3.9,0.06,4.9 --out plot_ro >out 2>err || rc=$?
ro_after=$(cd plot_ro && find . -print0 | sort -z | xargs -0 ls -ld --time-style=+ | awk '{$6=""; print}' | grep -v ' \.$')
if [ "$rc" -eq 2 ] && [ "$ro_before" = "$ro_after" ] && [ "$(cat plot_ro/evaluation.png)" = "old png" ] &&
   only_line_ok err "read-only" >/dev/null && grep -qF "plot_ro/evaluation.png" err; then
  pass "plot over a read-only old PNG: exit 2, '$(cat err)', the folder as it was"
else
  fail "plot over a read-only old PNG: exit $rc, $(cat err), $(ls -A plot_ro)"
fi

# report over a read-only old report.md: refused before the tunings (under
# 2 s, exit 2, one line), the old file kept.
mkdir -p report_ro && echo "old report" > report_ro/report.md && chmod 0444 report_ro/report.md
rc=0; start=$(date +%s%N)
"$pidlab" report --quick --no-figures --out report_ro >out 2>err || rc=$?
ms=$((($(date +%s%N) - start) / 1000000))
if [ "$rc" -eq 2 ] && [ "$ms" -lt 2000 ] && [ "$(cat report_ro/report.md)" = "old report" ] &&
   [ "$(ls -A report_ro)" = "report.md" ] && only_line_ok err "read-only" >/dev/null; then
  pass "report over a read-only old report.md: exit 2 in $ms ms, '$(cat err)', nothing written"
else
  fail "report over a read-only old report.md: exit $rc in $ms ms, $(cat err), $(ls -A report_ro)"
fi

echo "full_disk_test: $passed passed checks, $failed failed"
[ "$failed" -eq 0 ]
