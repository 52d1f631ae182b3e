#!/usr/bin/env bash
# Runs `pandora ARGS...` and checks the bad-input contract: exit code 2, exactly one line on stderr
# that contains EXPECTED (and the JSON path when given), and nothing left at OUT_DIR (removed before
# the run): no output, no staging file, no folder the command created.
# Usage: expect_error.sh PANDORA OUT_DIR EXPECTED -- ARGS...
set -u
pandora=$1; out_dir=$2; expected=$3; shift 3
[ "$1" = "--" ] && shift
rm -rf "$out_dir"
stderr_file=$(mktemp)
"$pandora" "$@" >/dev/null 2>"$stderr_file"
code=$?
err=$(cat "$stderr_file"); rm -f "$stderr_file"
fail() { echo "FAIL: $*"; echo "  command: $pandora $*"; echo "  stderr: $err"; exit 1; }
[ "$code" -eq 2 ] || fail "exit code $code, expected 2"
lines=$(printf '%s\n' "$err" | grep -c .)
[ "$lines" -eq 1 ] || fail "stderr has $lines lines, expected 1"
case "$err" in *"$expected"*) ;; *) fail "stderr does not contain '$expected'";; esac
# Nothing left behind: not a file, not even the (removed above) output folder itself.
if [ -e "$out_dir" ]; then
  leftovers=$(find "$out_dir" | head -5)
  fail "left behind: $leftovers"
fi
echo "ok: $err"
