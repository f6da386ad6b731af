#!/usr/bin/env bash
# The hostile-traffic harness at bench scale: every attack class of
# hostile_stranger against a live trio, MESSAGES in all (default 1e5),
# without and with a key, in a private network namespace.
#   bench/hostile_bench.sh [MESSAGES] [BIN_DIR]      (root; after scripts/build.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
messages=${1:-100008} bin=${2:-build/bin}
for mode in nokey key; do
  unshare -n bash tests/hostile/hostile_test.sh "$bin" "$mode" "$messages" | grep -E "^(hostile|PASS|FAIL)"
done
