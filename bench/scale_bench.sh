#!/usr/bin/env bash
# K trios on this machine: for K = 1, 2, 4, 8 (or the Ks given), one
# `pidlab launch --isolated --trios K` runs the tune of docs/trio.md's scaling table
#   pidlab tune --backend lcm --loop sampled --plant double_integrator
#     --horizon 5 --max-evals 80 --seed 3 --refine none --json   (TUNE_ARGS overrides)
# and measures its wall time, episodes/s, the CPU-seconds of every process
# (the tune itself, and the plants, controllers and disturbances of all K
# trios, from /proc/PID/stat), per step and per episode, and the efficiency
# (speed-up over K=1 divided by K). Every K must print the same gains, IAE
# and evaluations as the local sampled tune (checked). Prints a Markdown
# table for docs/trio.md.
#   bench/scale_bench.sh [BIN_DIR] [K...]        (root; after scripts/build.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-build/bin}")
shift || true
ks=("$@")
[ ${#ks[@]} -gt 0 ] || ks=(1 2 4 8)
tune_args=${TUNE_ARGS:---plant double_integrator --loop sampled --horizon 5 --method nelder-mead --max-evals 80 --seed 3 --refine none --json}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
key() { python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); print(j["gains"], j["iae"], j["evaluations"])' "$1"; }
"$bin/pidlab" tune $tune_args > "$tmp/local.json"
reference=$(key "$tmp/local.json")
echo "local sampled tune: $reference" >&2
export tune_args tmp
for k in "${ks[@]}"; do
  echo "K=$k ..." >&2
  "$bin/pidlab" launch --isolated --trios "$k" -- bash -c '
    cpu() {  # utime+stime ticks of a pid
      awk "{print \$14 + \$15}" /proc/$1/stat; }
    snapshot() {
      for i in $(seq 1 $PIDLAB_TRIOS); do
        for role in PLANT CONTROLLER DISTURBANCE; do
          v=PIDLAB_TRIO${i}_${role}_PID; echo "$role $(cpu ${!v})"; done; done; }
    snapshot > "$tmp/before"
    start=$(date +%s.%N)
    /usr/bin/time -f "%U %S" -o "$tmp/client.cpu" pidlab tune --backend lcm $tune_args > "$tmp/k.json"
    end=$(date +%s.%N)
    snapshot > "$tmp/after"
    echo "$start $end" > "$tmp/wall"' 2> "$tmp/launch.err" || { cat "$tmp/launch.err" >&2; exit 1; }
  got=$(key "$tmp/k.json")
  [ "$got" = "$reference" ] || { echo "K=$k gave $got, not $reference" >&2; exit 1; }
  python3 - "$k" "$tmp" >> "$tmp/rows" <<'PY'
import json, os, sys
k, tmp = int(sys.argv[1]), sys.argv[2]
hz = os.sysconf("SC_CLK_TCK")
start, end = map(float, open(f"{tmp}/wall").read().split())
wall = end - start
j = json.load(open(f"{tmp}/k.json"))
episodes = j["evaluations"]
args = os.environ["tune_args"].split()
flag = lambda name, default: float(args[args.index(name) + 1]) if name in args else default
steps_per_episode = round(flag("--horizon", 25.0) / flag("--dt", 1e-3)) + 1  # lockstep steps of one episode
cpu = {"client": sum(map(float, open(f"{tmp}/client.cpu").read().split()))}
before = [l.split() for l in open(f"{tmp}/before")]
after = [l.split() for l in open(f"{tmp}/after")]
for (role, b), (_, a) in zip(before, after):
    cpu[role.lower()] = cpu.get(role.lower(), 0.0) + (float(a) - float(b)) / hz
steps = episodes * steps_per_episode
total = sum(cpu.values())
print(json.dumps({"k": k, "wall": wall, "episodes": episodes, "steps": steps, "cpu": cpu, "total": total}))
PY
done
python3 - "$tmp/rows" "$(nproc)" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
cores = int(sys.argv[2])
base = next((r["wall"] for r in rows if r["k"] == 1), rows[0]["wall"] * rows[0]["k"])
print("| K | tune wall (s) | episodes/s | speed-up | efficiency | CPU us/step: client, plant, controller, disturbance, all | CPU ms/episode (all) |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    c, s = r["cpu"], r["steps"]
    us = lambda x: 1e6 * x / s
    speed = base / r["wall"]
    print(f"| {r['k']} | {r['wall']:.1f} | {r['episodes'] / r['wall']:.2f} | {speed:.2f} | {speed / r['k']:.2f} | "
          f"{us(c['client']):.1f}, {us(c['plant']):.1f}, {us(c['controller']):.1f}, {us(c['disturbance']):.1f}, "
          f"**{us(r['total']):.1f}** | {1e3 * r['total'] / r['episodes']:.0f} |")
# Where the cores saturate, and a projection from the measured CPU cost.
one = next((r for r in rows if r["k"] == 1), rows[0])
cpu_per_episode = one["total"] / one["episodes"]
wall_per_episode = one["wall"] / one["episodes"]
busy = cpu_per_episode / wall_per_episode  # cores one trio keeps busy
print()
print(f"{cores} cores here. One trio keeps {busy:.2f} cores busy ({1e3 * cpu_per_episode:.0f} ms of CPU per "
      f"{1e3 * wall_per_episode:.0f} ms episode), so about {cores / busy:.1f} trios saturate this machine. "
      f"On a machine with C cores, K trios speed a tune up by about min(K, C / {busy:.2f}) "
      f"(starts permitting), e.g. {min(8, 8 / busy):.1f}x for K = 8 on 8 cores, {min(16, 16 / busy):.1f}x for K = 16 on 16 cores.")
PY
