#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (unit, CLI and the
# LCM integration tests, each in its own private network namespace).
# A second, sanitised tree (build-asan/, -fsanitize=address,undefined) holds
# the processes, the decoders and the hostile-traffic tools: the hostile
# tests run against it too.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPIDLAB_SANITIZE=ON -DPIDLAB_WERROR=ON \
  -DPIDLAB_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j"$(nproc)" --target pidlab pidlab-plant pidlab-controller pidlab-disturbance \
  hostile_stranger hostile_protocol_test
bash scripts/build.sh -DPIDLAB_SANITIZED_BIN_DIR="$PWD/build-asan/bin"
cd build
ctest --output-on-failure --timeout 600
