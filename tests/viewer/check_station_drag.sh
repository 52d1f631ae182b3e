#!/usr/bin/env bash
# Moving a viewing station with the mouse (issue 11, point 7): `pandora view --script` under Xvfb on a
# copy of examples/trauma_room/viewing_station.json. A click on the station's eye picks it, a drag
# on the gizmo's x handle moves the eye 0.2 m along +x, a click on the display's centre and a drag on
# the z handle lower the display 0.05 m, Save writes both into the scene file with a backup.
# Checks the log (the mouse lands on pixels: within 2 mm), the saved file and the backup.
# Usage: check_station_drag.sh PANDORA OUT_DIR
set -euo pipefail
pandora=$1; out=$2
src=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$out"; mkdir -p "$out"
cp "$src"/examples/trauma_room/viewing_station.json "$out"/scene.json
sed "s|OUT/|$out/|g" "$src"/tests/viewer/station_drag.json > "$out"/script.json
run=("$(dirname "$0")"/with_xvfb.sh "$pandora" view "$out"/scene.json --script "$out"/script.json
     --hidden --size 960x540 --log "$out"/log.json)
"${run[@]}"

fail() { echo "FAIL: $*"; exit 1; }
near() { awk -v a="$1" -v b="$2" 'BEGIN { d = a - b; exit !(d < 0.002 && d > -0.002) }'; }
last=$(jq -c '.[-1]' "$out"/log.json)
eye_x=$(jq -r '.stations["remote consult"].eye[0]' <<<"$last")
display_z=$(jq -r '.stations["remote consult"].display_center[2]' <<<"$last")
echo "eye x $eye_x (expected 0.76), display z $display_z (expected 1.07)"
near "$eye_x" 0.76 || fail "the eye did not follow the x handle"
near "$display_z" 1.07 || fail "the display did not follow the z handle"
jq -e '.status | startswith("saved 1 viewing station into")' <<<"$last" >/dev/null || fail "not saved: $last"
# The file holds the moved eye and display (its facing point moved with it); the backup the original.
saved_eye=$(jq -r '.stations["remote consult"].eye[0]' "$out"/scene.json)
near "$saved_eye" 0.76 || fail "the scene file's eye is $saved_eye"
jq -e '.stations["remote consult"].display | (.facing[2] - .center[2] - 0.08 | fabs) < 1e-9' "$out"/scene.json >/dev/null ||
  fail "the display's facing point did not move with its centre"
cmp -s "$out"/scene.json.bak "$src"/examples/trauma_room/viewing_station.json || fail "no backup holds the original scene"
[ -s "$out"/moved.png ] || fail "no screenshot"
echo "ok: station drag"
