#!/usr/bin/env bash
# browser.bode_phase: the workbench's Bode plot of dead-time loops (issue 58)
# in Debian's headless Chromium at 1280x800 (tests/browser/bode_phase_test.js),
# in a private network namespace of its own (loopback only): on the tank, the
# motor and an integrating plant, each with its dead time, the drawn phase of
# L is the server's l_phase_deg and never jumps by more than 180 degrees
# between neighbouring points; its axis is clipped around the crossovers,
# with a note where the curve leaves it. The tank's Bode plot: OUT_DIR/bode-tank.png.
#   bode_phase_test.sh PIDLAB_BINARY SOURCE_DIR OUT_DIR
set -uo pipefail
if [[ $# -ne 3 ]]; then
  echo "usage: $0 PIDLAB_BINARY SOURCE_DIR OUT_DIR" >&2
  exit 2
fi
pidlab=$(realpath -- "$1") source_dir=$(realpath -- "$2") out_dir=$(realpath -m -- "$3")
script_args=("$@")
source "$(dirname -- "${BASH_SOURCE[0]}")/serve_page.sh"
serve_page_test bode_phase_test 110 'bode-*.png'
