#!/usr/bin/env bash
# The main job: install what is missing, build, then regenerate the paper's
# comparison (Tables II-VI, Figures 9-21, pidlab's own tunings, one episode
# over the LCM trio in a private network namespace) into out/report/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
build/bin/pidlab report --out out/report "$@"
echo "main job: report written to $(pwd)/out/report/report.md"
