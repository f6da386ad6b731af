#!/usr/bin/env bash
# Every episode field from what the user types to what the controllers see
# (episode_fields_walk.py): the Python keyword and the CLI flag echo it, the
# logged message carries it, `pidlab replay --json` reads it back, and the C
# and Python controllers print the same configuration, field by field.
# Run as: unshare -n bash episode_fields_test.sh BIN_DIR PYTHON_DIR SOURCE_DIR
set -uo pipefail
bin=$(realpath -- "${1:?usage: episode_fields_test.sh BIN_DIR PYTHON_DIR SOURCE_DIR}")
pydir=$(realpath -- "$2")
src=$(realpath -- "$3")

# Only in the private network namespace ctest made (unshare -n), multicast on its loopback.
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
private_network_up
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT; echo "work $work"
PYTHONPATH=$pydir PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 "$src/tests/integration/episode_fields_walk.py" \
  "$bin" "$src" "$work"
