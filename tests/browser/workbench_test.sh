#!/usr/bin/env bash
# browser.workbench: the workbench page of `pidlab serve` driven in Debian's
# headless Chromium by puppeteer-core (tests/browser/workbench_test.js), in a
# private network namespace of its own (loopback only, nothing leaves it):
# the page loads cleanly, the kp slider's IAE and step plot equal `pidlab
# evaluate --json` and `--samples-csv` for the three paper plants, two pinned
# designs, a --robust tuning from the page equals `pidlab tune --robust
# --json`, the page's command reruns to its IAE; screenshots under OUT_DIR.
#   workbench_test.sh PIDLAB_BINARY SOURCE_DIR OUT_DIR
set -uo pipefail
if [[ $# -ne 3 ]]; then
  echo "usage: $0 PIDLAB_BINARY SOURCE_DIR OUT_DIR" >&2
  exit 2
fi
pidlab=$(realpath -- "$1") source_dir=$(realpath -- "$2") out_dir=$(realpath -m -- "$3")
script_args=("$@")
source "$(dirname -- "${BASH_SOURCE[0]}")/serve_page.sh"
serve_page_test workbench_test 170 'workbench-*.png' --pidlab "$pidlab"
