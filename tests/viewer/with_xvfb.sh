#!/usr/bin/env bash
# Usage: with_xvfb.sh COMMAND [ARGS...]
# Runs COMMAND on a private X server and exits with COMMAND's own exit code. Xvfb picks a free
# display itself (-displayfd), so two servers never race for one number, and nothing of the
# server's start-up or clean-up can replace the command's code (xvfb-run exits 5 when it fails to
# remove its temporary folder, which once hid the viewer's exit 2 in CI). Without Xvfb the command
# runs on the current display.
set -u
command -v Xvfb >/dev/null || exec "$@"
number=$(mktemp)
Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>"$number" >/dev/null 2>&1 &
server=$!
for _ in $(seq 200); do
  [ -s "$number" ] && break
  kill -0 "$server" 2>/dev/null || break
  sleep 0.05
done
display=$(head -n 1 "$number")
rm -f "$number"
if [ -z "$display" ]; then
  kill "$server" 2>/dev/null
  echo "with_xvfb.sh: Xvfb did not start" >&2
  exit 1
fi
DISPLAY=":$display" "$@"
rc=$?
kill "$server" 2>/dev/null
wait "$server" 2>/dev/null
exit "$rc"
