#!/usr/bin/env bash
# integration.log_every_lane: docs/logs.md's recipe "Every lane with the stock
# tools" (its sh block, run as written: one stock lcm-logger per lane, a paced
# trio run by `pidlab launch`, the three files joined) must record the
# per-step messages: in `pidlab replay --json` of the joined log every
# PLANT_OUTPUT (y_0..y_N) and every CONTROL (u_0..u_{N-1}) of the episode is
# received from the lanes, and the base port's log alone holds none of them.
# A stock lcm-logger drops beyond 30 queued messages when the machine starves
# it (docs/logs.md, "Bursts"): a run with steps missing from the lane files is
# run again, at most 3 times, and said so; so is a run whose joined or base log
# is incomplete (a lost CONTROL, chunk or configuration).
# Run as: unshare -n bash lanes_test.sh BIN_DIR DOCS_LOGS_MD   (ctest does this)
set -uo pipefail

bin=$(realpath -- "${1:?usage: lanes_test.sh BIN_DIR DOCS_LOGS_MD}")
doc=$(realpath -- "${2:?usage: lanes_test.sh BIN_DIR DOCS_LOGS_MD}")
pidlab=$bin/pidlab

# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
private_network_up

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1

# The recipe: the first sh block after its heading, up to the next heading.
awk '/^### Every lane with the stock tools$/{on=1; next} on && /^#/ && !/^# /{on=0}
     on && /^```sh$/{code=1; next} code && /^```$/{exit} code' "$doc" >recipe.sh
if ! grep -q 'lcm-logger' recipe.sh || ! grep -q 'pidlab replay all.lcmlog' recipe.sh; then
  echo "FAIL docs/logs.md has no sh block under 'Every lane with the stock tools': $(head -c 300 recipe.sh)"
  exit 1
fi
mkdir -p build && ln -s "$bin" build/bin  # the recipe's build/bin/pidlab

# counts FILE: "RECEIVED_Y EXPECTED_Y RECEIVED_U EXPECTED_U COMPLETE" of the
# log's only episode, from pidlab replay --json.
counts() {
  "$pidlab" replay --json "$1" | python3 -c '
import json, sys
j = json.load(sys.stdin)
if len(j["episodes"]) != 1:
    sys.exit("%d episodes" % len(j["episodes"]))
e = j["episodes"][0]
print(e["plant_outputs"]["received"], e["plant_outputs"]["expected"],
      e["commands"]["received"], e["commands"]["expected"], e["complete"])'
}

for run in 1 2 3; do
  rm -f ./*.lcmlog
  if ! timeout 120 bash recipe.sh >recipe.out 2>recipe.err; then
    echo "FAIL the recipe exits non-zero: $(grep -v '^pidlab-' recipe.err | tail -3 | tr '\n' '|')"
    exit 1
  fi
  if ! all=$(counts all.lcmlog 2>&1) || ! base=$(counts base.lcmlog 2>&1); then
    # A configuration the base logger lost leaves no whole episode to count.
    echo "note: run $run: pidlab replay --json of the recipe's logs: ${all:-} / ${base:-}; running again"
    y=? want_y=? u=? want_u=? complete=? base_complete=?
    continue
  fi
  read -r y want_y u want_u complete <<<"$all"
  read -r base_y _ base_u _ base_complete <<<"$base"
  # The lanes' routing is wrong (not a loss): y or u on the base port, or no steps.
  if ((want_y < 2 || want_u < 1 || base_y != 0 || base_u != 0)); then
    echo "FAIL the recipe's logs: joined '$all', base port alone '$base' (wanted steps, no y or u on the base port)"
    exit 1
  fi
  # A starved stock logger drops datagrams on any port: a lost CONTROL leaves the
  # joined log incomplete, a lost chunk or configuration the base log; run again.
  if [[ $complete == True && $base_complete == True ]] && ((y == want_y && u == want_u)); then
    echo "PASS docs/logs.md's recipe, as written: the lanes' loggers hold all $y PLANT_OUTPUTs and $u CONTROLs" \
         "of the episode, the base port's logger none (run $run)"
    grep -q "plant outputs: $y/$want_y received" recipe.out && grep -q "commands: $u/$want_u received" recipe.out ||
      { echo "FAIL the recipe's pidlab replay does not say so: $(tr '\n' '|' <recipe.out | tail -c 600)"; exit 1; }
    echo "PASS its pidlab replay all.lcmlog says 'plant outputs: $y/$want_y received', 'commands: $u/$want_u received'"
    exit 0
  fi
  echo "note: run $run: the lanes' loggers kept $y of $want_y PLANT_OUTPUTs and $u of $want_u CONTROLs" \
       "(joined log complete: $complete, base log complete: $base_complete); running again"
done
echo "FAIL the loggers lost messages in 3 runs (last: $y of $want_y y, $u of $want_u u, complete $complete, base complete $base_complete)"
exit 1
