#!/usr/bin/env bash
# tools/lcm-spy builds a jar holding every pidlab LCM type (Java is optional:
# without javac/liblcm-java the test reports itself skipped, exit 77).
set -uo pipefail
spy=$(realpath -- "${1:?usage: lcm_spy_test.sh TOOLS_LCM_SPY}")
types=$(dirname "$spy")/../lcmtypes
if ! command -v javac >/dev/null || [[ ! -r /usr/share/java/lcm.jar ]]; then
  echo "SKIPPED: javac or liblcm-java missing (scripts/install-deps.sh installs them unless --no-java)"
  exit 77
fi
export XDG_CACHE_HOME=$(mktemp -d)
trap 'rm -rf "$XDG_CACHE_HOME"' EXIT
jar=$("$spy" --jar-path) || { echo "FAIL lcm-spy could not build the types jar"; exit 1; }
listing=$(unzip -l "$jar")
status=0
for f in "$types"/*.lcm; do
  name=$(basename "$f" .lcm)
  if grep -q "pidlab/$name.class" <<<"$listing"; then echo "PASS $name in the jar"
  else echo "FAIL $name missing from $jar"; status=1; fi
done
"$spy" --bogus >/dev/null 2>err.txt; rc=$?
if [[ $rc -eq 2 ]]; then echo "PASS bad argument exits 2"; else echo "FAIL bad argument exit $rc"; status=1; fi
rm -f err.txt
exit $status
