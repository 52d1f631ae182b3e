#!/usr/bin/env bash
# The viewer's Plan and Elevation views (docs/viewer.md, "Plans and elevations"): `pandora view
# --script` under Xvfb on the trauma room. {"view": "plan"}, a pan, {"view": "elevation", "side":
# "south"}, an orbit. Checks the log (the plan mode entered, kept by the pan, left by the orbit)
# and that each step changes the screenshot by more than the stated share. (The GPU picture against
# the exact CPU renderer's for the same PlanView: viewer.gl_renderer, TraumaRoomPlanMatchesCpu.)
# Usage: check_plan_view.sh PANDORA PNG_DIFF OUT_DIR
set -euo pipefail
pandora=$1; diff=$2; out=$3
src=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$out"; mkdir -p "$out"
cp "$src"/examples/trauma_room/scene.json "$out"/scene.json
sed "s|OUT/|$out/|g" "$src"/tests/viewer/plan_session.json > "$out"/script.json
xvfb=("$(dirname "$0")"/with_xvfb.sh)
"${xvfb[@]}" "$pandora" view "$out"/scene.json --rig octagon --script "$out"/script.json --hidden --size 960x540 \
  --log "$out"/log.json

fail() { echo "FAIL: $*"; exit 1; }
entry() { jq -c ".[] | select(.action == \"\$[$1]\")" "$out"/log.json; }
jq -e '.plan == "plan"' <<<"$(entry 3)" >/dev/null || fail "no plan: $(entry 3)"
jq -e '.plan == "plan"' <<<"$(entry 4)" >/dev/null || fail "the pan left the plan"
jq -e '.plan == "south"' <<<"$(entry 6)" >/dev/null || fail "no south elevation"
jq -e '.plan == ""' <<<"$(entry 8)" >/dev/null || fail "the orbit did not leave the elevation"
"$diff" "$out"/plan.png "$out"/plan_panned.png 1 8 >/dev/null && fail "the pan changed nothing on screen"
"$diff" "$out"/plan.png "$out"/elevation_south.png 5 8 >/dev/null && fail "the elevation looks like the plan"
"$diff" "$out"/elevation_south.png "$out"/orbit.png 5 8 >/dev/null && fail "the orbit changed nothing on screen"
echo "ok: plan and elevation views"
