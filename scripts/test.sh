#!/usr/bin/env bash
# Installs what is missing, builds, and runs the tests.
#   scripts/test.sh          every test (unit, cli, integration, install,
#                            hostile, browser, study): what .ci/run runs
#   scripts/test.sh --fast   the fast lane: build/ only, then the `unit` and
#                            `cli` labels (ctest -L 'unit|cli'), in parallel
# Every test's label is the first word of its name (tests/CMakeLists.txt).
# The LCM integration tests run each in its own private network namespace.
# For the full run a second, sanitised tree (build-asan/,
# -fsanitize=address,undefined) holds the processes, the decoders and the
# hostile-traffic tools: the hostile tests run against it too.
set -euo pipefail
cd "$(dirname "$0")/.."
fast=0
case "${1:-}" in
  --fast) fast=1 ;;
  "") ;;
  *) echo "usage: scripts/test.sh [--fast]" >&2; exit 2 ;;
esac
# The full run needs the processor-in-the-loop toolchain too (integration.pil, docs/pil.md).
if [ "$fast" = 1 ]; then bash scripts/install-deps.sh; else bash scripts/install-deps.sh --pil; fi
if [ "$fast" = 1 ]; then
  bash scripts/build.sh
  cd build
  start=$(date +%s)
  status=0
  ctest -L 'unit|cli' -j"$(nproc)" --output-on-failure --timeout 600 || status=$?
  echo "fast lane (ctest -L 'unit|cli'): $(( $(date +%s) - start )) s"
  exit "$status"
fi
# -O1 -g1: what the sanitisers' own documentation recommends, with line
# tables enough for a report's stack (and half the compile time of -O2 -g).
generator=()  # Ninja for a new tree, as scripts/build.sh
[ -f build-asan/CMakeCache.txt ] || ! command -v ninja >/dev/null 2>&1 || generator=(-G Ninja)
cmake -S . -B build-asan "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DPIDLAB_SANITIZE=ON -DPIDLAB_WERROR=ON -DPIDLAB_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j"$(nproc)" --target pidlab pidlab-plant pidlab-controller pidlab-disturbance \
  hostile_stranger hostile_protocol_test hostile_files
# No test runs the benchmark programs (bench/): the full run does not build
# them (about 17 s of compile CPU and four links); scripts/build.sh alone builds them again.
bash scripts/build.sh -DPIDLAB_SANITIZED_BIN_DIR="$PWD/build-asan/bin" -DPIDLAB_BUILD_BENCH=OFF
cd build
# In parallel: every test that starts processes does so in a private network
# namespace of its own, so two of them can run side by side; the ones that
# keep two processors busy by themselves (the hostile floods, the log
# mutants, the report) ask for both (PROCESSORS 2) and run alone.
ctest -j"$(nproc)" --output-on-failure --timeout 600
