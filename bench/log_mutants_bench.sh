#!/usr/bin/env bash
# The log mutator at bench scale: COUNT seeded mutants of a real log (default
# 1e4; CI runs 1000, tests/hostile/log_mutants_test.sh) against `pidlab
# replay`, every mutation class in turn, in a private network namespace (the
# seed log is recorded by a live trio). Peak RSS limit MAX_RSS_MB (default
# 200; give 600 for a sanitised BIN_DIR).
#   bench/log_mutants_bench.sh [COUNT] [BIN_DIR] [MAX_RSS_MB]   (root; after scripts/build.sh)
# Measured here (2 cores, build/bin, Release): see docs/security.md ("Damaged
# and hostile logs").
set -euo pipefail
cd "$(dirname "$0")/.."
count=${1:-10000} bin=${2:-build/bin} max_rss_mb=${3:-200}
unshare -n bash tests/hostile/log_mutants_test.sh "$bin" "$count" "$max_rss_mb" | grep -E "^(log_mutator|ok|PASS|FAIL)"
