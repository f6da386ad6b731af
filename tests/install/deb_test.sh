#!/usr/bin/env bash
# `cpack -G DEB` makes pidlab_<version>_amd64.deb: its control fields declare
# the Debian dependencies, its contents hold the executables, libraries,
# headers, messages, CMake package and pidlab.pc under /usr; unpacked with
# `dpkg -x` into a scratch directory, its pidlab answers --help, evaluates the
# paper's case like the build tree's pidlab, and runs an episode over its own
# trio (`pidlab launch` starts the processes next to itself).
# Run as: unshare -n bash deb_test.sh BUILD_DIR   (ctest does this)
set -uo pipefail
# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/../integration/lib.sh"
private_network_up
build=$(realpath -- "${1:?usage: deb_test.sh BUILD_DIR}")
pass=0; fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

version=$(sed -n 's/^set(CPACK_PACKAGE_VERSION "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
(cd "$build" && cpack -G DEB -B "$tmp/out" >"$tmp/cpack.log" 2>&1)
check "cpack -G DEB exits 0" "[ $? -eq 0 ]" || tail -5 "$tmp/cpack.log"
deb=$tmp/out/pidlab_${version}_amd64.deb
check "it made pidlab_${version}_amd64.deb" "[ -s '$deb' ]" || { echo "$fail failed"; exit 1; }

dpkg-deb --info "$deb" >"$tmp/info"
field() { dpkg-deb --field "$deb" "$1"; }
# The package names of a relationship field, one a line (alternatives too).
names() { field "$1" | tr ',|' '\n\n' | sed 's/ *(.*//; s/^ *//; s/ *$//'; }
check "Package is pidlab, Version $version, Architecture amd64" \
  "[ \"\$(field Package)\" = pidlab ] && [ \"\$(field Version)\" = '$version' ] && [ \"\$(field Architecture)\" = amd64 ]"
for dep in libc6 libstdc++6 liblcm1 libsodium23 libgoogle-glog0v6 libcholmod3 libcxsparse3 libspqr2 liblapack3 libatlas3-base; do
  check "Depends names $dep" "names Depends | grep -qx '$dep'"
done
for rec in liblcm-bin liblcm-dev libeigen3-dev libceres-dev libsodium-dev; do
  check "Recommends names $rec" "names Recommends | grep -qx '$rec'"
done
# Every library an executable needs is provided by a declared package
# (checked on this machine with ldconfig and dpkg -S).
dpkg-deb --contents "$deb" | awk '{print $6}' >"$tmp/contents"
for f in ./usr/bin/pidlab ./usr/bin/pidlab-plant ./usr/bin/pidlab-controller ./usr/bin/pidlab-disturbance \
         ./usr/lib/libpidlab_tune.a ./usr/include/pidlab/tune/tune.h ./usr/include/pidlab/lcmt_plant_output.hpp \
         ./usr/share/pidlab/lcmtypes/lcmt_plant_output.lcm ./usr/lib/cmake/pidlab/pidlabConfig.cmake \
         ./usr/lib/cmake/pidlab/pidlabTargets.cmake ./usr/lib/pkgconfig/pidlab.pc \
         ./usr/lib/python3/dist-packages/pidlab/lcmt_plant_output.py ./usr/share/pidlab/examples/python_controller.py; do
  check "contents hold $f" "grep -qx '$f' '$tmp/contents'"
done
check "contents hold the Python module" "grep -q '^./usr/lib/python3/dist-packages/pidlab/_pidlab\..*\.so$' '$tmp/contents'"
check "contents hold nothing outside /usr" "! grep -v '^\./usr/\|^\./$' '$tmp/contents' | grep -q ."

dpkg -x "$deb" "$tmp/root"
check "dpkg -x unpacks it" "[ -x '$tmp/root/usr/bin/pidlab' ]"
needed=$(for b in pidlab pidlab-plant pidlab-controller pidlab-disturbance; do
           objdump -p "$tmp/root/usr/bin/$b" | awk '/NEEDED/{print $2}'; done | sort -u)
for lib in $needed; do
  path=$(ldconfig -p | awk -v l="$lib" '$1 == l && /x86-64/ {print $NF; exit}')
  pkg=$( (dpkg -S "$path" || dpkg -S "$(readlink -f "$path")") 2>/dev/null | cut -d: -f1 | head -1)
  check "NEEDED $lib comes from $pkg, which Depends declares" \
    "[ -n '$pkg' ] && names Depends | grep -qx '$pkg'"
done

# The unpacked command line, with no LD_LIBRARY_PATH (pidlab's libraries are static).
unset LD_LIBRARY_PATH
"$tmp/root/usr/bin/pidlab" --help >"$tmp/help" 2>&1
check "unpacked pidlab --help exits 0 and lists evaluate" "[ $? -eq 0 ] && grep -q evaluate '$tmp/help'"
args=(evaluate --plant double_integrator --gains 29.6558,0.4977,28.3216 --json)
"$tmp/root/usr/bin/pidlab" "${args[@]}" >"$tmp/deb.json"
check "unpacked pidlab evaluate exits 0" "[ $? -eq 0 ]"
"$build/bin/pidlab" "${args[@]}" >"$tmp/build.json"
check "its JSON equals the build tree's, IAE $(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["iae"])' "$tmp/deb.json" 2>/dev/null)" \
  "cmp -s '$tmp/deb.json' '$tmp/build.json'"

PYTHONPATH=$tmp/root/usr/lib/python3/dist-packages /usr/bin/python3 -c '
import json, sys, pidlab
assert pidlab.evaluate("double_integrator", (29.6558, 0.4977, 28.3216)) == json.load(open(sys.argv[1]))' \
  "$tmp/build.json" 2>"$tmp/py.err"
check "the unpacked Python module evaluates like pidlab" "[ $? -eq 0 ]" || cat "$tmp/py.err"

# Its own trio: pidlab launch starts pidlab-plant, -controller and
# -disturbance from the unpacked usr/bin, in this private namespace.
lcm_args=(--plant oscillator --gains 2,1,1.5 --loop sampled --horizon 2 --json)
(cd "$tmp" && "$tmp/root/usr/bin/pidlab" launch -- pidlab evaluate --backend lcm "${lcm_args[@]}" \
   >"$tmp/lcm.json" 2>"$tmp/launch.err")
check "unpacked pidlab launch runs an episode over the unpacked trio" "[ $? -eq 0 ]" || tail -3 "$tmp/launch.err"
"$build/bin/pidlab" evaluate "${lcm_args[@]}" >"$tmp/local.json"
check "its IAE equals the in-process loop's bit for bit" "python3 - '$tmp/lcm.json' '$tmp/local.json' <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
assert a['backend'] == 'lcm' and a['iae'] == b['iae'], (a['iae'], b['iae'])
PY"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
