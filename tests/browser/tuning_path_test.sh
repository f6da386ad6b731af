#!/usr/bin/env bash
# browser.tuning_path: the workbench as the tuning app, from a CSV to C in the
# loop (docs/workbench.md, "From data to C"), in headless Chromium at
# 1280x800 while two busy loops load both cores, in a private network
# namespace of its own. tuning_path_test.js: a burst of requests of every
# kind each answered; the real TCLab step test uploaded, identified (auto),
# accepted, designed with the two knobs (= pidlab tune, 1e-12) and exported
# at the offered dt, the .c and .h downloaded. Then here: 6. gcc compiles the
# downloaded pidlab_pid.c into the trio's C controller role (controller/
# export/process/controller_role_c.c, lcm-gen -c's messages); 7. that
# controller next to pidlab launch --roles plant,disturbance gives the
# export's spec the same y, u, n at every step and IAE as pidlab evaluate
# --loop sampled in process, bit for bit.
#   tuning_path_test.sh PIDLAB_BINARY SOURCE_DIR BUILD_DIR OUT_DIR
set -uo pipefail
if [[ $# -ne 4 ]]; then
  echo "usage: $0 PIDLAB_BINARY SOURCE_DIR BUILD_DIR OUT_DIR" >&2
  exit 2
fi
pidlab=$(realpath -- "$1") source_dir=$(realpath -- "$2") build_dir=$(realpath -- "$3") out_dir=$(realpath -m -- "$4")
source "$(dirname -- "${BASH_SOURCE[0]}")/require_browser.sh" "$source_dir" || exit 1
if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
  PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "$@"
fi
. "$source_dir/tests/integration/lib.sh"
private_network_up
mkdir -p "$out_dir" && rm -f "$out_dir"/tuning-*.png
tmp=$(mktemp -d)
server= load=()
cleanup() {
  [ -n "$server" ] && kill "$server" 2>/dev/null
  for p in "${load[@]}"; do kill "$p" 2>/dev/null; done
  rm -rf "$tmp"
}
trap cleanup EXIT
"$pidlab" serve --port 0 --bind 127.0.0.1 --log-dir "$tmp" > "$tmp/serve.out" 2> "$tmp/serve.err" &
server=$!
wait_until 10 log_has "$tmp/serve.out" '^pidlab serve: http'
url=$(sed -n 's/^pidlab serve: //p' "$tmp/serve.out" | head -1)
[[ $url =~ ^http://127\.0\.0\.1:[0-9]+/ ]] || { echo "FAIL: pidlab serve printed no URL: $(head -c 300 "$tmp/serve.err")"; exit 1; }
# The CPU load: a busy loop per core, for the page's whole path.
for _ in 1 2; do (while :; do :; done) & load+=($!); done
timeout 400 node "$source_dir/tests/browser/tuning_path_test.js" --url "$url" --pidlab "$pidlab" \
  --modules "$source_dir/node_modules" --chromium "$chromium" --csv "$source_dir/tests/data/identify/tclab_step.csv" \
  --out "$out_dir" --tmp "$tmp"
status=$?
for p in "${load[@]}"; do kill "$p" 2>/dev/null; done
load=()
[ $status -eq 124 ] && echo "FAIL: the browser half did not finish in 400 s"
[ $status -eq 0 ] || exit 1
kill -0 "$server" 2>/dev/null || { echo "FAIL: pidlab serve is no longer running"; exit 1; }

# 6. The downloaded module compiled with gcc into the C controller role.
cd "$tmp" || exit 1
lcm_c=$build_dir/controller/export/process/lcmgen_c
if gcc -std=c99 -O2 -Wall -Wextra -Werror -ffp-contract=off -D_POSIX_C_SOURCE=200809L -Idownloads -I"$lcm_c" \
    -I"$build_dir/lcmtypes/lcmgen_cpp" -o controller-c "$source_dir/controller/export/process/controller_role_c.c" \
    downloads/pidlab_pid.c "$lcm_c"/pidlab_lcmt_*.c -w -llcm 2> gcc.err; then
  echo "ok   6. gcc compiles the downloaded pidlab_pid.c into the trio's C controller role"
else
  echo "FAIL 6. gcc refuses the downloaded module: $(head -c 600 gcc.err)"
  exit 1
fi
# 7. That controller in the trio against the in-process sampled loop.
lcm='udpm://239.255.76.67:7667?ttl=0'
"$pidlab" evaluate --spec export_spec.json --json --trajectory-csv local.csv > local.json 2> local.err ||
  { echo "FAIL 7. pidlab evaluate --spec (the export's) failed: $(head -c 300 local.err)"; exit 1; }
./controller-c --lcm-url "$lcm" 2> controller.err &
controller=$!
"$pidlab" launch --roles plant,disturbance --lcm-url "$lcm" -- \
  pidlab evaluate --backend lcm --spec export_spec.json --json --trajectory-csv trio.csv > trio.json 2> trio.err
rc=$?
kill -TERM "$controller" 2>/dev/null; wait "$controller" 2>/dev/null
if [ $rc -ne 0 ]; then
  echo "FAIL 7. the trio with the downloaded controller failed (exit $rc): $(tail -c 400 trio.err)"
  exit 1
fi
if /usr/bin/python3 - local.json trio.json <<'PY' && cmp -s local.csv trio.csv; then
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
assert a['iae'] is not None and a['iae'] == b['iae'] and a['ise'] == b['ise'], (a['iae'], b['iae'])
print('ok   7. the downloaded controller in the trio: IAE %r and y, u, n at all %d steps equal pidlab evaluate --loop sampled\'s, bit for bit (dt %r s)'
      % (a['iae'], sum(1 for _ in open('local.csv')) - 1, a['spec']['dt']))
PY
  exit 0
fi
echo "FAIL 7. the trio's trajectory or IAE differs from the in-process sampled loop's"
exit 1
