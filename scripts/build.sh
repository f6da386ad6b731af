#!/usr/bin/env bash
# Configures and builds pidlab into build/ (Release, every warning an error:
# -Wall -Wextra -Wpedantic -Wshadow with -DPIDLAB_WERROR=ON). Executables: build/bin/.
#   scripts/build.sh [EXTRA CMAKE ARGS...]
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPIDLAB_WERROR=ON "$@" >/dev/null
cmake --build build -j"$(nproc)"
