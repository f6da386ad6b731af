#!/usr/bin/env bash
# Hostile files against pidlab's file readers (tests/hostile/hostile_files.cc):
# COUNT cases a reader in process, then every EVERY'th of them through the
# command that reads it (--spec, export --from, --plant model:FILE,
# identify --csv, replay). Each command must exit 0, 1 or 2, without a crash
# or a sanitizer report, and a failure must say exactly one line of under
# 300 characters on stderr. BIN_DIR holds pidlab and hostile_files (a
# sanitised build-asan/bin has only the commands it builds: the others are
# left to the normal tree's run, and said so).
# usage: hostile_files_test.sh BIN_DIR COUNT EVERY
set -u
BIN=$(realpath -- "${1:?usage: hostile_files_test.sh BIN_DIR COUNT EVERY}")
COUNT=${2:?usage} EVERY=${3:?usage}
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
failures=0
mkdir -p "$TMP/samples"
"$BIN/hostile_files" --count "$COUNT" --samples "$TMP/samples" --sample-every "$EVERY" || fail "hostile_files"

has() { "$BIN/pidlab" "$1" --help >/dev/null 2>&1; }
runs=0
check() {  # check FILE COMMAND...
  local file=$1; shift
  local rc=0
  timeout 60 "$@" >"$TMP/out" 2>"$TMP/err" </dev/null || rc=$?
  runs=$((runs + 1))
  if [ "$rc" -gt 2 ]; then
    fail "$(basename "$file"): exit $rc from $*: $(head -c 300 "$TMP/err")"
    return
  fi
  if [ "$rc" -ne 0 ]; then
    local lines chars
    lines=$(wc -l <"$TMP/err")
    chars=$(tail -n 1 "$TMP/err" | wc -c)
    if [ "$lines" -ne 1 ] || [ "$chars" -gt 300 ]; then
      fail "$(basename "$file"): exit $rc with $lines lines, the last $chars characters: $(head -c 400 "$TMP/err")"
    fi
  fi
}
for f in "$TMP"/samples/spec_*.json; do check "$f" "$BIN/pidlab" evaluate --spec "$f"; done
for f in "$TMP"/samples/model_*.json; do check "$f" "$BIN/pidlab" evaluate --plant "model:$f" --gains 1,0.1,0; done
for f in "$TMP"/samples/log_*.lcmlog; do check "$f" "$BIN/pidlab" replay "$f"; done
if has export; then
  for f in "$TMP"/samples/result_*.json; do check "$f" "$BIN/pidlab" export --from "$f" --lang c --out "$TMP/export"; done
else
  echo "note: $BIN/pidlab has no export (a sanitised tree): results read in process only"
fi
if has identify; then
  for f in "$TMP"/samples/csv_*.csv; do check "$f" "$BIN/pidlab" identify --csv "$f" --model p1d --starts 2; done
else
  echo "note: $BIN/pidlab has no identify (a sanitised tree): CSVs read in process only"
fi
echo "$runs command runs on the samples"
[ "$runs" -ge 5 ] || fail "only $runs command runs"
echo "hostile_files_test: $failures failures"
[ "$failures" -eq 0 ]
