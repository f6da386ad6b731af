#!/usr/bin/env bash
# The cost of the exported controller on the emulated Cortex-M3 and M4F
# (docs/pil.md's table): for each scalar and core, pidlab export --pil, then
# the oscillator's 2500 steps in the trio with the firmware as the controller
# (pidlab launch --controller pil:DIR, in a private network namespace), and
# the bridge's report: instructions per step (QEMU -icount, emulated), the
# stack's painted high-water mark, and the ELF's sections. Prints the
# markdown table.
# usage: bench/pil_bench.sh [BIN_DIR]   (default build/bin; needs scripts/install-deps.sh --pil)
set -euo pipefail
bin=$(cd "${1:-build/bin}" && pwd)
if [ "${PIDLAB_IN_NETNS:-}" != 1 ]; then
  exec unshare -n env PIDLAB_IN_NETNS=1 bash "$0" "$bin"
fi
ip link set lo up; ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
flags="--plant oscillator --gains 2,1,1.5 --output-limits -10,10 --dt 0.01"
echo "| scalar | core | instructions per step, mean (max) | stack, bytes | text, bytes | data + bss, bytes |"
echo "|---|---|---|---|---|---|"
for scalar in double float q31 q15; do
  range=(); case $scalar in q31|q15) range=(--input-range -2,2) ;; esac
  for core in m3 m4f; do
    dir="$tmp/$scalar.$core"
    "$bin/pidlab" export $flags --lang c --out "$dir" --scalar $scalar "${range[@]}" --pil $core >/dev/null
    "$bin/pidlab" launch --controller "pil:$dir" -- "$bin/pidlab" evaluate --backend lcm --loop sampled $flags \
      >"$dir.out" 2>&1
    /usr/bin/python3 - "$dir" "$scalar" "$core" <<'PY'
import json, sys
d, scalar, core = sys.argv[1:4]
r, b = json.load(open(d + "/pil_report.json")), json.load(open(d + "/pil.json"))
i = r["instructions_per_step"]
print("| %s | %s | %.0f (%d) | %d | %d | %d |" % (scalar, "Cortex-M3" if core == "m3" else "Cortex-M4F",
      i["mean"], i["max"], r["stack_bytes"], b["text_bytes"], b["data_bytes"] + b["bss_bytes"]))
PY
  done
done
