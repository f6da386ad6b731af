#!/usr/bin/env bash
# Processor in the loop (docs/pil.md), in the private network namespace
# ctest gives it (unshare -n): the exported controller built by
# `pidlab export --pil` for the emulated Cortex-M3 (mps2-an385) and Cortex-M4F
# (mps2-an386), run as the trio's controller by `pidlab launch --controller
# pil:DIR`, against pidlab-controller-c built on this host from the same
# module: every command (the trajectory, bit for bit) and the IAE, on the
# oscillator and the stepper, in q31, q15 and float; one run lossy,
# authenticated and logged. Then a damaged firmware (a
# wrong frame), a stalled one, and QEMU killed: one line naming it, the trio
# stopped, no QEMU and no zombie left.
# usage: pil_test.sh BIN_DIR LCM_C_DIR LCM_FIELDS_DIR
set -uo pipefail
bin=$1 lcm_c=$2 fields=$3
src="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
. "$src/tests/integration/lib.sh"
private_network_up
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
for tool in arm-none-eabi-gcc arm-none-eabi-size qemu-system-arm; do
  command -v $tool >/dev/null || { echo "FAIL $tool is not installed: run scripts/install-deps.sh --pil"; exit 1; }
done
url='udpm://239.255.76.67:7667?ttl=0'
for f in "$lcm_c"/*.c; do gcc -std=c99 -O2 -w -c "$f" -I"$lcm_c" -o "$(basename "$f" .c).o" || echo "FAIL lcm-gen C: $f"; done

# plant: its flags, the module's limits and input range
declare -A plant_flags=(
  [oscillator]="--plant oscillator --gains 2,1,1.5 --output-limits -10,10 --dt 0.01"
  [stepper]="--plant stepper --gains 20.8836,26.607,12.4866 --output-limits -100,100 --dt 1e-4 --horizon 0.5"
)
for plant in oscillator stepper; do
  flags=${plant_flags[$plant]}
  for scalar in q31 q15 float; do
    range=(); [ $scalar != float ] && range=(--input-range -2,2)
    # The host reference: pidlab-controller-c around the same module.
    "$bin/pidlab" export $flags --lang c --out "host.$plant.$scalar" --scalar $scalar "${range[@]}" >/dev/null 2>&1 ||
      echo "FAIL export $plant $scalar"
    gcc -std=c99 -O2 -Wall -Wextra -Werror -ffp-contract=off -D_POSIX_C_SOURCE=200809L -I"host.$plant.$scalar" \
      -I"$lcm_c" -I"$fields" "$src/controller/export/process/controller_role_c.c" "host.$plant.$scalar/pidlab_pid.c" \
      ./*.o -llcm -lm -o "ctl.$plant.$scalar" 2>cc.err || echo "FAIL host controller $plant $scalar: $(head -c 400 cc.err)"
    "./ctl.$plant.$scalar" --lcm-url "$url" 2>/dev/null & pc=$!
    "$bin/pidlab" launch --roles plant,disturbance --lcm-url "$url" -- "$bin/pidlab" evaluate --backend lcm --loop sampled \
      $flags --trajectory-csv "host.$plant.$scalar.csv" >"host.$plant.$scalar.out" 2>&1 ||
      echo "FAIL the host run $plant $scalar: $(tail -1 "host.$plant.$scalar.out")"
    kill -TERM $pc; wait $pc
    host_iae=$(awk '/^IAE/ {print $NF}' "host.$plant.$scalar.out")
    for core in m3 m4f; do
      dir="pil.$plant.$scalar.$core"
      "$bin/pidlab" export $flags --lang c --out "$dir" --scalar $scalar "${range[@]}" --pil $core >"$dir.export" 2>&1 ||
        echo "FAIL export --pil $core $plant $scalar: $(tail -1 "$dir.export")"
      "$bin/pidlab" launch --controller "pil:$dir" -- "$bin/pidlab" evaluate --backend lcm --loop sampled $flags \
        --trajectory-csv "$dir.csv" >"$dir.out" 2>&1 || echo "FAIL the PIL run $plant $scalar $core: $(grep -m1 pil "$dir.out")"
      iae=$(awk '/^IAE/ {print $NF}' "$dir.out")
      steps=$(($(wc -l <"$dir.csv") - 1))
      if cmp -s "host.$plant.$scalar.csv" "$dir.csv" && [ -n "$iae" ] && [ "$iae" = "$host_iae" ]; then
        echo "PASS $plant, $scalar on the emulated $core: all $steps commands and the IAE $iae equal pidlab-controller-c's on the host bit for bit ($(tail -1 "$dir.export" | sed 's/ reserved//'))"
      else
        echo "FAIL $plant, $scalar on $core: IAE $iae against the host's $host_iae; $(cmp "host.$plant.$scalar.csv" "$dir.csv" 2>&1 | head -1)"
      fi
      /usr/bin/python3 - "$dir/pil_report.json" "$steps" <<'PY' || echo "FAIL $dir: no cost report"
import json, sys
r, steps = json.load(open(sys.argv[1])), int(sys.argv[2])
i = r["instructions_per_step"]
ok = r["steps"] == steps and 40 <= i["mean"] <= i["max"] and i["max"] % 40 == 0 and 0 < r["stack_bytes"] < r["stack_reserved"]
print(("PASS " if ok else "FAIL ") + "%s: %d steps cost %.0f instructions each (max %d, emulated), stack %s of %s bytes" %
      (sys.argv[1].split("/")[0], r["steps"], i["mean"], i["max"], r["stack_bytes"], r["stack_reserved"]))
PY
    done
  done
done

# The rest of the trio unchanged around the firmware: 5 % of the messages dropped in every process, every
# message authenticated, the run logged; the commands still equal the host's, and the log replays complete.
head -c 32 /dev/urandom >trio.key; chmod 600 trio.key
"$bin/pidlab" launch --controller pil:pil.oscillator.q31.m4f --drop-rate 0.05 --auth-key trio.key --log run.lcmlog -- \
  "$bin/pidlab" evaluate --backend lcm --loop sampled ${plant_flags[oscillator]} --trajectory-csv lossy.csv >lossy.out 2>&1 ||
  echo "FAIL the lossy, authenticated PIL run: $(tail -1 lossy.out)"
"$bin/pidlab" replay run.lcmlog --auth-key trio.key --json >replay.json 2>replay.err || echo "FAIL replay: $(tail -1 replay.err)"
/usr/bin/python3 - <<'PY'
import json
eps = json.load(open("replay.json"))["episodes"]
same = open("lossy.csv").read() == open("host.oscillator.q31.csv").read()
ok = same and len(eps) >= 1 and all(e["complete"] for e in eps) and any(e["commands"].get("duplicates", 0) > 0 for e in eps)
print(("PASS " if ok else "FAIL ") + "with 5 %% of the messages dropped, every message authenticated and the run logged, the "
      "q31 firmware on the M4F gives the host's commands bit for bit (%s), and the log replays complete (%d episode(s), "
      "commands %s)" % (same, len(eps), [e["commands"] for e in eps]))
PY

# The deadline check: the stepper's q31 step on the M3 at 25 MHz fits its 100 us dt; at 5 MHz it does not,
# and the bridge says so once and counts the steps over (pidlab-controller-pil --core-clock-hz).
for hz in 25e6 5e6; do
  "$bin/pidlab-controller-pil" --lcm-url "$url" --firmware "$PWD/pil.stepper.q31.m3/pil.elf" --core m3 \
    --core-clock-hz $hz --report "deadline.$hz.json" 2>"deadline.$hz.err" & pc=$!
  "$bin/pidlab" launch --roles plant,disturbance --lcm-url "$url" -- "$bin/pidlab" evaluate --backend lcm \
    --loop sampled ${plant_flags[stepper]} >/dev/null 2>&1 || echo "FAIL the deadline run at $hz Hz"
  kill -TERM $pc; wait $pc
done
/usr/bin/python3 - <<'PY'
import json
fit, slow = json.load(open("deadline.25e6.json"))["deadline"], json.load(open("deadline.5e6.json"))["deadline"]
line = open("deadline.5e6.err").read().strip().splitlines()
said = [l for l in line if "deadline:" in l]
ok = fit["steps_over_dt"] == 0 and fit["worst_fraction_of_dt"] < 1 and slow["steps_over_dt"] == 5000 and len(said) == 1 \
     and not any("deadline:" in l for l in open("deadline.25e6.err"))
print(("PASS " if ok else "FAIL ") + "the deadline check: at 25 MHz the worst step takes %.2f of dt, at 5 MHz %d of 5000 "
      "steps are over, said once: %s" % (fit["worst_fraction_of_dt"], slow["steps_over_dt"], said[0].split(": ", 1)[1] if said else None))
PY

# A damaged, a stalled and a killed firmware: one line naming it, the trio stopped, nothing left behind.
fault() {  # fault NAME NEEDLE [CFLAGS]
  local name=$1 needle=$2 cflags=${3:-}
  PIDLAB_PIL_CFLAGS="$cflags" "$bin/pidlab" export ${plant_flags[oscillator]} --lang c --out "fault.$name" \
    --scalar q31 --input-range -2,2 --pil m3 >/dev/null 2>&1 || echo "FAIL export fault $name"
  "$bin/pidlab" launch --controller "pil:fault.$name" -- "$bin/pidlab" evaluate --backend lcm --loop sampled \
    ${plant_flags[oscillator]} --max-attempts 1 >"fault.$name.out" 2>&1 & lp=$!
  if [ "$name" = killed ]; then
    for _ in $(seq 100); do pgrep -x qemu-system-arm >/dev/null && break; sleep 0.1; done
    sleep 1; pkill -KILL -x qemu-system-arm
  fi
  wait $lp; rc=$?
  sleep 0.5
  local line; line=$(grep -m1 "pidlab-controller-pil: episode" "fault.$name.out")
  local left; left=$(pgrep -x qemu-system-arm | wc -l)
  # Zombies of this run only: a QEMU, or a child of this shell. Other tests
  # (ctest -j2) have short-lived zombies of their own between exit and reap.
  local zombies; zombies=$(ps -eo stat=,ppid=,comm= | awk -v me=$$ \
    '$1 ~ /^Z/ && ($3 ~ /^qemu-system/ || $2 == me) { n++ } END { print n + 0 }')
  if [ $rc != 0 ] && grep -q "$needle" <<<"$line" && [ "$left" = 0 ] && [ "$zombies" = 0 ] &&
     grep -q "pidlab-controller-pil (pid [0-9]*) exited with status 1" "fault.$name.out"; then
    echo "PASS a $name firmware: launch exit $rc, one line: ${line#*: }; no QEMU, no zombie"
  else
    echo "FAIL a $name firmware: exit $rc, line '$line', $left QEMU left, $zombies zombies: $(tail -3 "fault.$name.out")"
  fi
}
fault damaged "a wrong frame from the firmware" "-DPIL_FAULT=1 -DPIL_FAULT_STEP=100"
fault stalled "did not answer within the 2 s deadline" "-DPIL_FAULT=2 -DPIL_FAULT_STEP=100"
fault killed "QEMU was killed by signal 9"
