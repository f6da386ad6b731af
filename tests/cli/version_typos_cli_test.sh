#!/usr/bin/env bash
# A newcomer's first minutes (README.md): `pidlab --version` and `pidlab
# version` print the project version and the git commit of the build
# (cmake/PidlabBuildInfo.cmake, run at every build); a mistyped subcommand or
# option is named with the closest valid one, in the one-line, exit-2 shape of
# README.md's "Exit status and limits", and with no suggestion when nothing
# is close.
# Usage: version_typos_cli_test.sh PIDLAB_BINARY PROJECT_VERSION SOURCE_DIR CMAKE BUILD_INFO_SCRIPT
set -uo pipefail
source "$(dirname -- "$0")/stderr_shape.sh"  # only_line_ok: the one-line stderr rule

if [[ $# -ne 5 ]]; then
  echo "usage: $0 PIDLAB_BINARY PROJECT_VERSION SOURCE_DIR CMAKE BUILD_INFO_SCRIPT" >&2
  exit 2
fi
pidlab=$(realpath -- "$1") version=$2 source_dir=$(realpath -- "$3") cmake=$4 script=$(realpath -- "$5")
[[ -x $pidlab ]] || { echo "FAIL: $pidlab is not an executable"; exit 1; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
passed=0 failed=0
pass() { echo "ok   $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

# ---- pidlab --version, pidlab version ----
# The commit the tree is at now; the binary must have been built from it (a
# stale binary fails here: rebuild). Outside git the build says "unknown".
if head=$(git -C "$source_dir" rev-parse --short=12 HEAD 2>/dev/null) &&
   [[ $(realpath "$(git -C "$source_dir" rev-parse --show-toplevel)") == "$source_dir" ]]; then
  want_commit=$head
else
  want_commit=unknown
fi
for form in --version version; do
  status=0
  "$pidlab" $form >out 2>err || status=$?
  line=$(cat out)
  if ((status != 0)) || [[ -s err ]] || (($(wc -l <out) != 1)); then
    fail "pidlab $form: exit $status, stdout '$(head -c 200 out)', stderr '$(head -c 200 err)'"
  elif [[ ! $line =~ ^pidlab\ ([^ ]+)\ \(commit\ ([0-9a-f]{12}|unknown)(,\ modified)?\)$ ]]; then
    fail "pidlab $form: '$line' is not 'pidlab VERSION (commit HASH[, modified])'"
  elif [[ ${BASH_REMATCH[1]} != "$version" ]]; then
    fail "pidlab $form says version ${BASH_REMATCH[1]}, CMake's project version is $version"
  elif [[ ${BASH_REMATCH[2]} != "$want_commit" ]]; then
    fail "pidlab $form says commit ${BASH_REMATCH[2]}, $source_dir is at $want_commit (a stale build?)"
  else
    pass "pidlab $form: $line"
  fi
done
"$pidlab" --help >help.out 2>&1
if grep -qE '^  version +Print the version' help.out && grep -qE '^  --version +print the version' help.out; then
  pass "pidlab --help lists the version subcommand and --version"
else
  fail "pidlab --help does not list 'version' and '--version': $(tr '\n' '|' <help.out | head -c 600)"
fi

# ---- The build's script: the commit, ", modified", "unknown", rewritten only on a change ----
# run_script DIR: what PidlabBuildInfo.cmake makes GitCommit() return for DIR.
run_script() {
  "$cmake" -DSOURCE_DIR="$1" -DOUTPUT="$work/info.cc" -DVERSION="$version" -P "$script" >/dev/null 2>&1 &&
    sed -n 's/.*GitCommit() { return "\(.*\)"; }.*/\1/p' "$work/info.cc"
}
mkdir repo plain
git_in() { git -C "$work/repo" -c user.name=test -c user.email=test@example.invalid "$@" >/dev/null 2>&1; }
git_in init -q && echo a >repo/file && git_in add file && git_in commit -q -m first
first=$(git -C repo rev-parse --short=12 HEAD)
got=$(run_script "$work/repo")
[[ $got == "$first" ]] && pass "a git tree: its commit ($got)" || fail "a git tree at $first: '$got'"
touch -d 2000-01-01 info.cc
got=$(run_script "$work/repo")
if [[ $got == "$first" && $(stat -c %Y info.cc) == $(date -d 2000-01-01 +%s) ]]; then
  pass "the same commit again: the generated source is not rewritten (nothing rebuilds)"
else
  fail "the same commit again: '$got', rewritten: $(stat -c %y info.cc)"
fi
echo b >repo/file && git_in commit -q -a -m second
second=$(git -C repo rev-parse --short=12 HEAD)
got=$(run_script "$work/repo")
[[ $got == "$second" && $second != "$first" ]] && pass "a new commit is picked up ($got)" ||
  fail "a new commit $second: '$got'"
echo c >repo/file
got=$(run_script "$work/repo")
[[ $got == "$second, modified" ]] && pass "a changed tracked file: '$got'" || fail "a changed tracked file: '$got'"
echo d >repo/untracked && git_in checkout -q file
got=$(run_script "$work/repo")
[[ $got == "$second" ]] && pass "an untracked file is no modification: '$got'" || fail "an untracked file: '$got'"
mkdir repo/unpacked
got=$(run_script "$work/repo/unpacked")
[[ $got == unknown ]] && pass "a tree unpacked inside another repository: unknown" ||
  fail "a tree inside another repository: '$got'"
got=$(GIT_CEILING_DIRECTORIES=$work run_script "$work/plain")
[[ $got == unknown ]] && pass "a tree outside git: unknown" || fail "a tree outside git: '$got'"

# ---- Typos: one line, exit 2, the closest valid name when one is close ----
# typo WHAT WANT ARGS...: exit 2, stderr exactly the line WANT, nothing on stdout.
typo() {
  local what=$1 want=$2 status=0 why
  shift 2
  timeout 5 "$pidlab" "$@" >typo.out 2>typo.err || status=$?
  if ((status != 2)); then
    fail "$what: exit $status (stderr: $(head -c 300 typo.err))"
  elif ! why=$(only_line_ok typo.err "error:"); then
    fail "$what: $why"
  elif [[ $(cat typo.err) != "$want" ]]; then
    fail "$what: '$(cat typo.err)', wanted '$want'"
  elif [[ -s typo.out ]]; then
    fail "$what: wrote to stdout"
  else
    pass "$what: $want"
  fi
}
typo "an option with two letters swapped" \
  "pidlab tune: error: unknown option '--plnat' (did you mean --plant?)" tune --plnat stepper
typo "the same with =VALUE" \
  "pidlab tune: error: unknown option '--plnat' (did you mean --plant?)" tune --plnat=stepper
typo "an option with a letter changed, after good ones" \
  "pidlab evaluate: error: unknown option '--gainz' (did you mean --gains?)" evaluate --plant linear --gainz 1,1,1
typo "an option before launch's -- COMMAND (whose own flags are not pidlab's)" \
  "pidlab launch: error: unknown option '--drop-rat' (did you mean --drop-rate?)" launch --drop-rat 0.1 -- bash -c true
typo "a subcommand with a letter changed" "pidlab: error: 'tunr' is not a subcommand (did you mean tune?)" tunr
typo "a subcommand with a letter missing" \
  "pidlab: error: 'evalute' is not a subcommand (did you mean evaluate?)" evalute --plant linear
typo "pidlab's own option" "pidlab: error: unknown option '--verison' (did you mean --version?)" --verison
typo "an option nothing is close to" \
  "pidlab tune: error: unknown option '--zzzzzzzz' (pidlab tune --help)" tune --plant linear --zzzzzzzz 1
typo "a one-letter option" "pidlab replay: error: unknown option '-q' (pidlab replay --help)" replay run.lcmlog -q
commands=$("$pidlab" --help | sed -n '/^Subcommands:/,$s/^  \([a-z]\+\) .*/\1/p' | paste -sd, | sed 's/,/, /g')
typo "a subcommand nothing is close to" \
  "pidlab: error: 'frobnicate' is not a subcommand ($commands; pidlab --help)" frobnicate --x 1
# A stray value (not an option) keeps CLI11's words.
status=0
"$pidlab" evaluate --plant linear --gains 1,1,1 stray >/dev/null 2>typo.err || status=$?
if ((status == 2)) && only_line_ok typo.err "not expected: stray" >/dev/null && ! grep -q "did you mean" typo.err; then
  pass "a stray value: $(cat typo.err)"
else
  fail "a stray value: exit $status, $(head -c 300 typo.err)"
fi

# Every long option of every subcommand, two of its letters swapped, is named
# with an option of that subcommand (its own --help), in one line, exit 2.
# Each suggestion is an option of the subcommand's --help; most are the
# option itself.
# is_option NAME: NAME is one of ${options[@]} (no pipe: under pipefail a
# `grep -q` that stops early fails its printf with SIGPIPE).
is_option() { [[ " ${options[*]} " == *" $1 "* ]]; }
tried=0 itself=0 bad_ones=""
for command in ${commands//,/}; do
  mapfile -t options < <("$pidlab" "$command" --help | sed -nE 's/^  (-[a-zA-Z],)?(--[a-z][a-z0-9-]+).*/\2/p' | sort -u)
  for option in "${options[@]}"; do
    name=${option#--}
    ((${#name} >= 5)) || continue
    mangled="--${name:0:2}${name:3:1}${name:2:1}${name:4}"
    [[ $mangled == "$option" ]] && continue
    is_option "$mangled" && continue
    status=0
    timeout 5 "$pidlab" "$command" "$mangled" 1 >/dev/null 2>typo.err || status=$?
    tried=$((tried + 1))
    suggested=$(sed -n "s/^pidlab $command: error: unknown option '$mangled' (did you mean \(--[a-z0-9-]*\)?)$/\1/p" typo.err)
    if ((status != 2)) || (($(wc -l <typo.err) != 1)) || [[ -z $suggested ]] ||
       ! is_option "$suggested"; then
      bad_ones+=" $command $mangled (exit $status: $(head -c 200 typo.err));"
    fi
    [[ $suggested == "$option" ]] && itself=$((itself + 1))
  done
done
if ((tried < 50)) || [[ -n $bad_ones ]]; then
  fail "options with two letters swapped ($tried tried):${bad_ones:- fewer than 50 options found}"
else
  pass "$tried options of every subcommand with two letters swapped: each named with an option of its subcommand, $itself with itself"
fi

echo "$passed passed, $failed failed"
((failed == 0))
