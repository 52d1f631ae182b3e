#!/usr/bin/env bash
# A PTZ camera in the viewer (issue 13; docs/ptz.md, "In the viewer"): `pandora view --script` under
# Xvfb on a copy of examples/ptz_home/scene.json. The dome goes to pan 63, tilt -3, zoom 40 degrees
# (the west door); the trace mode "path" is picked with the Camera panel's radio button (a mouse
# click), then "all" with a 1.5 s budget; the panel's Re-centre button (a click) makes the west door
# home; pan -20; save. Checks the log (the setting, the shifted ranges), the saved file (pivot,
# zoom, ptz block, presets), the backup, and that each trace changes the picture.
# Usage: check_ptz_view.sh PANDORA PNG_DIFF OUT_DIR
set -euo pipefail
pandora=$1; diff=$2; out=$3
src=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$out"; mkdir -p "$out"
cp "$src"/examples/ptz_home/scene.json "$out"/scene.json
sed "s|OUT/|$out/|g" "$src"/tests/viewer/ptz_session.json > "$out"/script.json
run=("$(dirname "$0")"/with_xvfb.sh "$pandora" view "$out"/scene.json --script "$out"/script.json
     --hidden --size 960x540 --log "$out"/log.json)
"${run[@]}"

fail() { echo "FAIL: $*"; exit 1; }
entry() { jq -c ".[] | select(.action == \"\$[$1]\")" "$out"/log.json; }
jq -e '.ptz_trace == "path"' <<<"$(entry 8)" >/dev/null || fail "the path radio button did not pick the path trace"
jq -e '.ptz_trace == "all"' <<<"$(entry 10)" >/dev/null || fail "no all trace"
recentred=$(entry 21)
jq -e '.undo == "re-centre dome" and .cameras[0].ptz.pan_deg == 0 and .cameras[0].ptz.tilt_deg == 0
       and (.cameras[0].ptz.tilt_range_deg | (.[0] + 72 | fabs) < 1e-9 and (.[1] - 13 | fabs) < 1e-9)
       and (.cameras[0].ptz.presets[1].pan_deg | fabs) < 1e-9' <<<"$recentred" >/dev/null ||
  fail "the Re-centre button did not re-centre the dome: $recentred"
jq -e '.status | startswith("saved 1 camera into")' <<<"$(entry 23)" >/dev/null || fail "not saved: $(entry 23)"
# The file: the pivot where it was, the zoom, the head's setting, ranges and presets shifted.
dome=$(jq -c '.rigs[0].cameras[0]' "$out"/scene.json)
jq -e '.position == [0, -2.3, 2.45] and .hfov_deg == 40 and .ptz.pan_deg == -20 and .ptz.tilt_deg == 0
       and .ptz.tilt_range_deg == [-72, 13] and .ptz.pan_range_deg == [-243, 117]
       and .ptz.presets[1].pan_deg == 0 and .ptz.presets[1].tilt_deg == 0 and .ptz.presets[0].pan_deg == -63
       and (.ptz.tour | length) == 4' <<<"$dome" >/dev/null || fail "the saved dome: $dome"
jq -e '.rigs[1] == $orig.rigs[1] and .objects == $orig.objects and .views == $orig.views' --argjson orig "$(cat "$src"/examples/ptz_home/scene.json)" "$out"/scene.json >/dev/null || fail "the save changed more than the dome"
cmp -s "$out"/scene.json.bak "$src"/examples/ptz_home/scene.json || fail "no backup holds the original scene"
# Each trace lights more of the room than the one before.
"$diff" "$out"/1_single.png "$out"/2_path.png 1 8 >/dev/null && fail "the path trace changed nothing on screen"
"$diff" "$out"/2_path.png "$out"/3_all.png 1 8 >/dev/null && fail "the all trace changed nothing on screen"
# The window's background (progressive) all trace ends in the exact picture a screenshot renders.
"$diff" "$out"/3_all_progressive.png "$out"/3_all.png 0 0 || fail "the background all trace is not the exact one"
echo "ok: PTZ session"
