#!/usr/bin/env bash
# `pidlab launch --log` under a full CPU load at bench scale: RUNS logged
# launches (default 50; CI runs 20, hostile.launch_log_keeps_every_
# configuration_under_load) of EVALUATIONS evaluations with a disturbance
# each (default 3: 6 episodes), beside two busy loops and a second trio
# running episodes back to back, in a private network namespace. Every run's
# log must hold every episode's configuration, complete.
#   bench/log_under_load.sh [RUNS] [EVALUATIONS] [BIN_DIR]   (root; after scripts/build.sh)
# Measured here (2 cores, build/bin, Release): see docs/trio.md ("A complete
# log is guaranteed").
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-50} evaluations=${2:-3} bin=${3:-build/bin}
unshare -n bash tests/hostile/log_under_load_test.sh "$bin" "$runs" "$evaluations"
