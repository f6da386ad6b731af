#!/usr/bin/env bash
# Configures and builds pidlab into build/ (Release, every warning an error:
# -Wall -Wextra -Wpedantic -Wshadow with -DPIDLAB_WERROR=ON). Executables: build/bin/.
# The benchmark programs are built (-DPIDLAB_BUILD_BENCH=ON) unless an extra
# argument says otherwise: the full test run passes OFF, as no test runs them.
#   scripts/build.sh [EXTRA CMAKE ARGS...]
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPIDLAB_WERROR=ON -DPIDLAB_BUILD_BENCH=ON "$@" >/dev/null
cmake --build build -j"$(nproc)"
