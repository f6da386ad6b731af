#!/usr/bin/env bash
# `cmake --install` into a fresh prefix, then examples/consumer (an
# out-of-tree project: find_package(pidlab CONFIG REQUIRED)) configured,
# built and run against it; the same main.cc compiled with
# `pkg-config --cflags --libs pidlab`; their numbers equal, bit for bit, those
# of the installed `pidlab evaluate --json` and `pidlab tune --json`.
# usage: install_consumer_test.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
src=$1 build=$2
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix

cmake --install "$build" --prefix "$prefix" >"$tmp/install.log" 2>&1
check "cmake --install into a fresh prefix exits 0" "[ $? -eq 0 ]"
for f in bin/pidlab bin/pidlab-plant bin/pidlab-controller bin/pidlab-disturbance \
         lib/libpidlab_tune.a lib/libpidlab_transport.a include/pidlab/tune/tune.h \
         include/pidlab/transport/protocol.h include/pidlab/lcmt_control_command.hpp \
         share/pidlab/lcmtypes/lcmt_control_command.lcm lib/cmake/pidlab/pidlabConfig.cmake \
         lib/cmake/pidlab/pidlabConfigVersion.cmake lib/cmake/pidlab/pidlabTargets.cmake lib/pkgconfig/pidlab.pc \
         lib/python3/dist-packages/pidlab/lcmt_control_command.py share/pidlab/examples/python_controller.py \
         share/pidlab/examples/consumer/main.cc; do
  check "installs $f" "[ -e '$prefix/$f' ]"
done
check "the exported targets carry the pidlab:: namespace" \
  "grep -q 'add_library(pidlab::tune STATIC IMPORTED)' '$prefix/lib/cmake/pidlab/pidlabTargets.cmake'"
check "the installed headers name no build or source directory" \
  "! grep -rqF -e '$src' -e '$build' '$prefix/include' '$prefix/lib/cmake' '$prefix/lib/pkgconfig'"

check "the installed Python messages encode and decode with /usr/bin/python3" \
  "PYTHONPATH='$prefix/lib/python3/dist-packages' /usr/bin/python3 -c 'from pidlab.lcmt_plant_output import lcmt_plant_output as M; m = M(); m.y = 0.5; assert M.decode(m.encode()).y == 0.5'"

# The CLI of the install gives the reference numbers. examples/consumer calls
# Tune() with TuneOptions' defaults (eq. (4)'s 25 s at 0.05 s, an ideal
# derivative, the box [0, 30]); on a custom plant the command line derives
# the time scale and widens a box it was not given whose optimum is on the
# edge (docs/tuning.md), so the tune asks for all of them explicitly.
"$prefix/bin/pidlab" evaluate --plant double_integrator --gains 29.6558,0.4977,28.3216 --json >"$tmp/eval.json"
check "installed pidlab evaluate --json exits 0" "[ $? -eq 0 ]"
"$prefix/bin/pidlab" tune --num 1 --den 1,0,1 --max-evals 400 --horizon 25 --sample-time 0.05 \
  --derivative-filter-ratio 0 --bounds 0,30 --json >"$tmp/tune.json" 2>/dev/null
check "installed pidlab tune --json exits 0" "[ $? -eq 0 ]"
PYTHONPATH="$prefix/lib/python3/dist-packages" /usr/bin/python3 -c '
import json, sys, pidlab
ev = pidlab.evaluate("double_integrator", (29.6558, 0.4977, 28.3216))
assert ev == json.load(open(sys.argv[1])), "differs"' "$tmp/eval.json" 2>"$tmp/py.err"
check "the installed Python module evaluates like the installed CLI" "[ $? -eq 0 ]" || cat "$tmp/py.err"

compare() {  # compare NAME OUTPUT_FILE
  python3 - "$tmp/eval.json" "$tmp/tune.json" "$2" <<'PY'
import json, re, sys
ev, tu = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
out = open(sys.argv[3]).read()
got = {k: float(v) for k, v in re.findall(r'(\w+)=([-+0-9.eE]+)', out.split('\n')[0])}
assert got['iae'] == ev['iae'], (got['iae'], ev['iae'])
assert got['overshoot_pct'] == ev['overshoot_pct'], (got, ev['overshoot_pct'])
assert got['stable'] == 1
got = {k: float(v) for k, v in re.findall(r'(\w+)=([-+0-9.eE]+)', out.split('\n')[1])}
for k in ('kp', 'ki', 'kd'):
    assert got[k] == tu['gains'][k], (k, got[k], tu['gains'][k])
assert got['objective'] == tu['objective'], (got['objective'], tu['objective'])
print('   evaluate iae %r, tune %r objective %r' % (ev['iae'], tu['gains'], tu['objective']))
PY
}

# find_package(pidlab CONFIG REQUIRED) from the fresh prefix only.
cmake -S "$src/examples/consumer" -B "$tmp/consumer" -DCMAKE_PREFIX_PATH="$prefix" \
      -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_BUILD_TYPE=Release >"$tmp/configure.log" 2>&1
check "examples/consumer configures against the prefix" "[ $? -eq 0 ]" || cat "$tmp/configure.log"
check "it found the prefix's package" "grep -qx 'pidlab_DIR:PATH=$prefix/lib/cmake/pidlab' '$tmp/consumer/CMakeCache.txt'"
cmake --build "$tmp/consumer" -j2 >"$tmp/build.log" 2>&1
check "examples/consumer builds" "[ $? -eq 0 ]" || tail -20 "$tmp/build.log"
"$tmp/consumer/pidlab_consumer" >"$tmp/consumer.out" 2>&1
check "examples/consumer runs" "[ $? -eq 0 ]" || cat "$tmp/consumer.out"
check "its IAE and tuned gains equal pidlab's JSON bit for bit" "compare cmake '$tmp/consumer.out'"

# pkg-config: the same program from the flags alone.
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
check "pkg-config finds pidlab $(pkg-config --modversion pidlab 2>/dev/null)" "pkg-config --exists pidlab"
check "its includedir is the prefix's" \
  "[ \"\$(realpath \"\$(pkg-config --variable=includedir pidlab)\")\" = \"\$(realpath $prefix/include)\" ]"
g++ -std=c++17 -O1 "$src/examples/consumer/main.cc" -o "$tmp/pc_consumer" \
    $(pkg-config --cflags --libs pidlab) >"$tmp/pc.log" 2>&1
check "main.cc compiles and links with pkg-config --cflags --libs pidlab" "[ $? -eq 0 ]" || tail -20 "$tmp/pc.log"
"$tmp/pc_consumer" >"$tmp/pc.out" 2>&1
check "the pkg-config build gives the same numbers" "compare pkg-config '$tmp/pc.out'"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
