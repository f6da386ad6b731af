#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (unit, CLI and the
# LCM integration tests, each in its own private network namespace).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
cd build
ctest --output-on-failure --timeout 600
