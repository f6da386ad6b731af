#!/usr/bin/env bash
# Logs and replay end to end: one episode with a disturbance under
# `pidlab launch --isolated --log`, then `pidlab replay` must reproduce the
# live IAE exactly and call the log complete, --redrive must pass, `pidlab plot
# --log` must draw the logged data, and damaged copies of the log (cut tail,
# garbage events, corrupt tail, an altered command) must be reported clearly.
# Run as: unshare -n bash replay_test.sh BIN_DIR   (ctest does this)
set -uo pipefail

bin=$(realpath -- "${1:?usage: replay_test.sh BIN_DIR}")
pidlab=$bin/pidlab
tamper=$bin/replay_log_tamper
export PATH=$bin:$PATH

# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
private_network_up

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
failed=0
pass() { echo "PASS $1"; }
fail() { echo "FAIL $1"; failed=1; }

# ---- a live episode, logged ----
# `pidlab launch --log` guarantees a complete log (it repairs what lcm-logger
# lost from the plant's trajectory chunks, or fails): one run, no retry.
flags=(--plant oscillator --gains 2,1,1.5 --loop sampled --dt 0.001 --horizon 4 --disturbance square
       --disturbance-amplitude 0.2 --disturbance-period 1)
if ! "$pidlab" launch --isolated --log run.lcmlog -- \
    pidlab evaluate --backend lcm "${flags[@]}" --json --trajectory-csv live.csv >live.json 2>launch.err; then
  fail "launch failed: $(grep -v '^pidlab-' launch.err | tail -3)"
  exit 1
fi
if "$pidlab" replay run.lcmlog >first.txt 2>&1 && ! grep -q INCOMPLETE first.txt; then
  pass "launch --isolated --log ran the episode and logged every step$(grep -o '; repaired.*' launch.err)"
else
  fail "launch handed over an incomplete log: $(grep INCOMPLETE first.txt | cut -c1-300)"
  exit 1
fi

# ---- replay: exact IAE, complete ----
status=0
"$pidlab" replay run.lcmlog --json >replay.json 2>replay.err || status=$?
if [[ $status -eq 0 ]] && python3 - live.json replay.json <<'PY'
import json, sys
live = json.load(open(sys.argv[1]))
rep = json.load(open(sys.argv[2]))
assert rep["clean_end"], "log not read cleanly to the end"
disturbed = [e for e in rep["episodes"] if e.get("disturbance") not in (None, "none")]
assert len(disturbed) == 1, f"expected one disturbed episode, got {len(disturbed)}"
e = disturbed[0]
assert e["complete"], e["completeness"]
assert e["evaluation"]["iae"] == live["iae"], (e["evaluation"]["iae"], live["iae"])
assert e["evaluation"]["iae_undisturbed"] == live["iae_undisturbed"]
for other in rep["episodes"]:
    assert other["complete"], other["completeness"]
print("replayed IAE", repr(e["evaluation"]["iae"]), "== live", repr(live["iae"]))
PY
then
  pass "replay reproduces the live IAE exactly and reports the episode complete"
else
  fail "replay IAE/completeness (status $status): $(cat replay.err)"
fi

# ---- table output ----
"$pidlab" replay run.lcmlog >replay.txt 2>&1
if grep -q "complete" replay.txt && ! grep -q "INCOMPLETE" replay.txt; then
  pass "replay table lists the episodes as complete"
else
  fail "replay table: $(cat replay.txt)"
fi

# ---- the logged trajectory is the live one, step by step ----
id=$(python3 -c 'import json,sys; print([e["episode_id"] for e in json.load(open("replay.json"))["episodes"] if e.get("disturbance") != "none"][0])')
if "$pidlab" replay run.lcmlog --episode "$id" --csv replay.csv >/dev/null 2>&1 && python3 - live.csv replay.csv <<'PY'
import csv, sys
live = list(csv.DictReader(open(sys.argv[1])))
rep = {int(r["k"]): r for r in csv.DictReader(open(sys.argv[2]))}
assert len(live) > 1000
for row in live:
    k = int(row["k"])
    for col in ("y", "u", "n"):
        a, b = float(row[col]), float(rep[k][col])
        assert a == b or (a != a and b != b), f"step {k} {col}: live {a!r} log {b!r}"
print(len(live), "steps identical")
PY
then
  pass "replay --csv holds the live trajectory bit for bit"
else
  fail "replay --csv differs from the live trajectory"
fi

# ---- redrive ----
status=0
"$pidlab" replay run.lcmlog --redrive >redrive.txt 2>&1 || status=$?
if [[ $status -eq 0 ]] && [[ $(grep -c "redrive: OK, all .* reproduced bit for bit" redrive.txt) -ge 1 ]]; then
  pass "--redrive reproduces every logged command"
else
  fail "--redrive on the honest log (status $status): $(cat redrive.txt)"
fi

# ---- plot from the log ----
if "$pidlab" plot --log run.lcmlog --episode "$id" --out figs --width 900 --height 700 >plot.out 2>plot.err &&
   python3 - figs/run.png figs/run_data replay.csv <<'PY'
import csv, struct, sys
png, data, rep = sys.argv[1], sys.argv[2], sys.argv[3]
b = open(png, "rb").read(24)
assert b[:8] == b"\x89PNG\r\n\x1a\n" and b[12:16] == b"IHDR", "not a PNG"
w, h = struct.unpack(">II", b[16:24])
assert (w, h) == (900, 700), (w, h)
rows = {int(r["k"]): r for r in csv.DictReader(open(rep))}
# Panel 0: reference (s0) and y (s1); panel 2: u (s0).
for panel, col in (("p0_s1", "y"), ("p2_s0", "u")):
    pts = [l.split() for l in open(f"{data}/{panel}.dat") if l.strip() and not l.startswith("#")]
    assert len(pts) == len(rows) - 1, (panel, len(pts), len(rows))
    for k, (t, v) in enumerate(pts):
        a, b = float(v), float(rows[k][col])
        assert a == b or (a != a and b != b), (panel, k, v, rows[k][col])
print("png", w, "x", h, "data match")
PY
then
  pass "plot --log draws episode ${id}: PNG of the requested size, data = the logged trajectory"
else
  fail "plot --log: $(cat plot.err)"
fi

# ---- a log cut off mid-write ----
# Cut 20 bytes into the first event that starts after 3/5 of the file, so the
# cut is always inside an event (a fixed byte count sometimes lands exactly on
# an event boundary, which is a clean end, not a cut).
cut=$(python3 -c '
import sys
b = open("run.lcmlog", "rb").read()
i = b.find(bytes.fromhex("EDA1DA01"), len(b) * 3 // 5)
assert i > 0
print(i + 20)')
head -c "$cut" run.lcmlog >cut.lcmlog
status=0
"$pidlab" replay cut.lcmlog >cut.txt 2>&1 || status=$?
if [[ $status -eq 0 ]] && grep -q "cut off mid-write" cut.txt && grep -q "INCOMPLETE" cut.txt &&
   grep -q "NOT read cleanly" cut.txt; then
  pass "a truncated log is read up to the cut, which is reported"
else
  fail "truncated log (status $status): $(cat cut.txt)"
fi

# ---- garbage events and a corrupt tail ----
"$tamper" run.lcmlog garbage.lcmlog inject-garbage || fail "tamper inject-garbage"
printf '\xed\xa1\xda\x01\x00\x00\x00\x00\x00\x00\x00\x07junkjunkjunk' >>garbage.lcmlog
status=0
"$pidlab" replay garbage.lcmlog --json >garbage.json 2>garbage.err || status=$?
"$pidlab" replay garbage.lcmlog >garbage.txt 2>&1
if [[ $status -eq 0 ]] && grep -q "STRANGER_POSE" garbage.txt && grep -q "unknown fingerprint" garbage.txt &&
   grep -q "do not decode" garbage.txt && grep -q "tail is corrupt" garbage.txt &&
   python3 - live.json garbage.json <<'PY'
import json, sys
live = json.load(open(sys.argv[1]))
rep = json.load(open(sys.argv[2]))
e = [e for e in rep["episodes"] if e.get("disturbance") != "none"][0]
assert e["complete"] and e["evaluation"]["iae"] == live["iae"]
assert rep["foreign_events"] > 0 and rep["unknown_type_events"] > 0 and rep["decode_failures"] > 0
PY
then
  pass "garbage events and a corrupt tail are reported; the episode still replays exactly"
else
  fail "garbage log (status $status): $(cat garbage.txt | head -8)"
fi

# ---- an altered command ----
"$tamper" run.lcmlog altered.lcmlog alter-command 1234 || fail "tamper alter-command"
status=0
"$pidlab" replay altered.lcmlog --episode "$id" --redrive >altered.txt 2>altered.err || status=$?
if [[ $status -eq 1 ]] && grep -q "redrive: FAILED, first mismatch at step 1234 " altered.txt &&
   grep -q "logged u = .*, recomputed u = " altered.txt && [[ $(wc -l <altered.err) -eq 1 ]] &&
   grep -q "^pidlab replay: .*--redrive: 1 of 1 episodes did not reproduce; episode $id: first mismatch at step 1234 " altered.err; then
  pass "--redrive points at the altered command (step 1234) with both values, and says why in one line"
else
  fail "--redrive on the altered log (status $status): $(cat altered.txt altered.err)"
fi

# ---- forged events of three episodes whose configuration is in no log ----
"$tamper" run.lcmlog orphan.lcmlog inject-orphan || fail "tamper inject-orphan"
status=0
"$pidlab" replay orphan.lcmlog --redrive >orphan.txt 2>orphan.err || status=$?
real=$(grep -c "redrive: OK, all .* reproduced bit for bit" orphan.txt)
if [[ $status -eq 0 ]] && [[ $real -ge 1 ]] && [[ $real -eq $(grep -c "redrive: OK" redrive.txt) ]] &&
   grep -q "redrive: SKIPPED, episode 987654321 has no configuration in the log" orphan.txt && [[ ! -s orphan.err ]]; then
  pass "--redrive with orphan events: the $real real episode(s) reproduce (exit 0), each orphan is named and skipped"
else
  fail "--redrive with orphan events (status $status): $(cat orphan.txt orphan.err | head -20)"
fi
status=0
"$pidlab" plot --log orphan.lcmlog --out plot_orphans >/dev/null 2>plot_orphans.err || status=$?
if [[ $status -eq 0 ]] && [[ $(grep -c "not plotted" plot_orphans.err) -eq 1 ]] &&
   grep -q "^note: 3 episodes (987654321, 987654322, 987654323) not plotted: no episode configuration" plot_orphans.err &&
   [[ $(sort plot_orphans.err | uniq -d | wc -l) -eq 0 ]]; then
  pass "plot --log with three orphans: one line per distinct note, naming the three"
else
  fail "plot --log with three orphans (status $status): $(head -c 600 plot_orphans.err)"
fi

# ---- redrive against a live controller (started alone in this namespace) ----
"$bin/pidlab-controller" -v >controller.log 2>&1 &
controller=$!
wait_until 10 log_has controller.log "serving on" || fail "pidlab-controller did not start: $(tail -2 controller.log)"
status=0
"$pidlab" replay run.lcmlog --episode "$id" --redrive --backend lcm >live_redrive.txt 2>&1 || status=$?
if [[ $status -eq 0 ]] && grep -q "redrive: OK, all .* by the live controller" live_redrive.txt; then
  pass "--redrive --backend lcm: the live pidlab-controller reproduces every logged command"
else
  fail "--redrive --backend lcm on the honest log (status $status): $(tail -2 live_redrive.txt)"
fi
status=0
"$pidlab" replay altered.lcmlog --episode "$id" --redrive --backend lcm >live_altered.txt 2>&1 || status=$?
if [[ $status -eq 1 ]] && grep -q "first mismatch at step 1234 " live_altered.txt; then
  pass "--redrive --backend lcm points at the altered command (step 1234)"
else
  fail "--redrive --backend lcm on the altered log (status $status): $(tail -2 live_altered.txt)"
fi
kill "$controller" 2>/dev/null
wait "$controller" 2>/dev/null

# ---- bad input ----
status=0
"$pidlab" replay no-such.lcmlog >bad.out 2>bad.err || status=$?
if [[ $status -eq 2 ]] && [[ $(wc -l <bad.err) -eq 1 ]] && grep -q "no-such.lcmlog" bad.err; then
  pass "a missing log is one line and exit 2"
else
  fail "missing log: status $status, $(cat bad.err)"
fi

exit $failed
