# Sourced by the CLI tests: the stderr rule of README.md ("Exit status and
# limits"). A failing command ends with exactly one line on stderr, under 300
# characters, naming the cause; bad input prints nothing else.
#
# final_line_ok FILE NEEDLE: the last line of FILE is shorter than 300
#   characters, holds NEEDLE, and is the only line that says "error:" or
#   "failed:". Prints the reason and returns 1 if not.
# only_line_ok FILE NEEDLE: the same, and FILE has exactly one line.

final_line_ok() {
  local file=$1 needle=$2 last chars errors
  last=$(tail -n 1 "$file")
  chars=${#last}
  errors=$(grep -c -E '(error|failed): ' "$file")
  if [[ -z $last ]]; then
    echo "stderr is empty (wanted one line with '$needle')"
    return 1
  fi
  if ((chars >= 300)); then
    echo "the last stderr line has $chars characters: $last"
    return 1
  fi
  if [[ $last != *"$needle"* ]]; then
    echo "the last stderr line does not name '$needle': $last"
    return 1
  fi
  if ((errors != 1)); then
    echo "$errors lines say error/failed (wanted 1, the last): $(tr '\n' '|' <"$file")"
    return 1
  fi
  return 0
}

only_line_ok() {
  local file=$1 needle=$2 lines
  lines=$(wc -l <"$file")
  if ((lines != 1)); then
    echo "stderr has $lines lines (wanted 1): $(tr '\n' '|' <"$file")"
    return 1
  fi
  final_line_ok "$file" "$needle"
}

# bad_input_ok NEEDLE COMMAND...: COMMAND exits 2, prints nothing on stdout,
#   and its stderr is one line naming NEEDLE (only_line_ok). Prints "exit 2:"
#   and that line and returns 0; else prints the reason and returns 1. Leaves
#   the command's stdout and stderr in ./bad.out and ./bad.err.
bad_input_ok() {
  local needle=$1 status=0 why
  shift
  "$@" >bad.out 2>bad.err || status=$?
  if ((status != 2)); then
    echo "exit $status, expected 2 ($(head -c 300 bad.err))"
    return 1
  fi
  if ! why=$(only_line_ok bad.err "$needle"); then
    echo "$why"
    return 1
  fi
  if [[ -s bad.out ]]; then
    echo "bad input wrote to stdout: $(head -c 200 bad.out)"
    return 1
  fi
  echo "exit 2: $(cat bad.err)"
}
