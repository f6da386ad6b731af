#!/usr/bin/env bash
# Configures and builds pidlab into build/ (Release, every warning an error:
# -Wall -Wextra -Wpedantic -Wshadow with -DPIDLAB_WERROR=ON). Executables: build/bin/.
# The benchmark programs are built (-DPIDLAB_BUILD_BENCH=ON) unless an extra
# argument says otherwise: the full test run passes OFF, as no test runs them.
#   scripts/build.sh [EXTRA CMAKE ARGS...]
set -euo pipefail
cd "$(dirname "$0")/.."
# A new tree is generated for Ninja (Debian's ninja-build, which
# install-deps.sh installs): it schedules the two processors across every
# target's objects at once, where make's recursive build keeps one target's
# objects together (a clean Release tree: 378 s against 412 s with make,
# docs/benchmarks.md). A tree configured before keeps its generator.
generator=()
[ -f build/CMakeCache.txt ] || ! command -v ninja >/dev/null 2>&1 || generator=(-G Ninja)
cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DPIDLAB_WERROR=ON -DPIDLAB_BUILD_BENCH=ON "$@" >/dev/null
cmake --build build -j"$(nproc)"
