# Sourced by a browser test's .sh: serve_page_test NAME SECONDS SCREENSHOTS [NODE ARGS...]
# with the script's own arguments in PIDLAB_BINARY SOURCE_DIR OUT_DIR (set by
# the caller as pidlab, source_dir, out_dir). It re-runs the script in a
# private network namespace of its own (loopback only), removes OUT_DIR's old
# SCREENSHOTS (a glob), starts `pidlab serve --port 0` on 127.0.0.1, runs
# tests/browser/NAME.js with node (--url, --modules, --chromium, --out, --tmp
# and the NODE ARGS) within SECONDS, and exits with its status (1 if the
# server died or no URL was printed).
serve_page_test() {
  local name=$1 seconds=$2 screenshots=$3
  shift 3
  # Not a skip: without the browser or the npm packages the test fails, with one line.
  source "$(dirname -- "${BASH_SOURCE[0]}")/require_browser.sh" "$source_dir" || exit 1
  if [[ ${PIDLAB_TEST_IN_NAMESPACE:-} != 1 ]]; then
    PIDLAB_TEST_IN_NAMESPACE=1 exec unshare -n bash "$0" "${script_args[@]}"
  fi
  ip link set lo up || { echo "FAIL: cannot bring up the private namespace's loopback"; exit 1; }
  mkdir -p "$out_dir" && rm -f "$out_dir"/$screenshots  # no stale screenshot from an earlier run
  tmp=$(mktemp -d)
  server=
  trap '[ -n "$server" ] && kill "$server" 2>/dev/null; rm -rf "$tmp"' EXIT
  "$pidlab" serve --port 0 --bind 127.0.0.1 > "$tmp/serve.out" 2> "$tmp/serve.err" &
  server=$!
  for _ in $(seq 200); do grep -q '^pidlab serve: http' "$tmp/serve.out" && break; sleep 0.05; done
  local url
  url=$(sed -n 's/^pidlab serve: //p' "$tmp/serve.out" | head -1)
  if [[ ! $url =~ ^http://127\.0\.0\.1:[0-9]+/ ]]; then
    echo "FAIL: pidlab serve --port 0 printed no URL on 127.0.0.1: $(head -c 300 "$tmp/serve.out" "$tmp/serve.err")"
    exit 1
  fi
  # Bounded: the whole test well under ctest's TIMEOUT.
  timeout "$seconds" node "$source_dir/tests/browser/$name.js" \
    --url "$url" --modules "$source_dir/node_modules" --chromium "$chromium" --out "$out_dir" --tmp "$tmp" "$@"
  local status=$?
  [ $status -eq 124 ] && echo "FAIL: the browser test did not finish in $seconds s"
  kill -0 "$server" 2>/dev/null || { echo "FAIL: pidlab serve is no longer running"; status=1; }
  exit $status
}
