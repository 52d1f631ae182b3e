#!/usr/bin/env bash
# `pandora propose` against the layouts people start from (docs/propose.md, issue 32):
# - mocap lab (12 cameras, both people at six poses, >= 3 cameras on body points): the best
#   proposal beats the best of the ring, grid, wall-grid and along generators by 5 points and is at
#   least as good as the bundled hand-made corners rig, all judged on the same points;
# - trauma room (8 cameras, the neck region, >= 2 cameras): at least as good as the paper's grid4x2.
# --iterations makes the search the same on any machine.
# Usage: check_propose_examples.sh PANDORA EXAMPLES_DIR WORK_DIR
set -u
pandora=$1; examples=$2; work=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$work"; mkdir -p "$work"
cp -r "$examples/mocap_lab" "$work/mocap"
s="$work/mocap/scene.json"
lens=(--resolution 2048x1536 --hfov 66)
"$pandora" rig "$s" --name gen_ring --ring 12 --radius 2.3 --height 2.6 "${lens[@]}" -q || fail ring
"$pandora" rig "$s" --name gen_grid --grid 4,3 --rect=-3,-2,3,2 --height 2.8 --aim 0,0,0.9 "${lens[@]}" -q || fail grid
"$pandora" rig "$s" --name gen_wall_grid --wall-grid 6,2 --wall=-3.5,2.5,3.5,2.5 --z-range 1.8,2.6 "${lens[@]}" -q || fail wall-grid
"$pandora" rig "$s" --name gen_along --along=-3.5,-2.5,3.5,-2.5,3.5,2.5,-3.5,2.5,-3.5,-2.5 --count 12 --height 2.6 "${lens[@]}" -q || fail along
start=$(date +%s%N)
"$pandora" propose "$s" --cameras 12 --objective coverage3 --iterations 100000 --compare all --out "$work/mocap_out" -q || fail "propose mocap"
echo "mocap: $(awk "BEGIN { print ($(date +%s%N) - $start) / 1e9 }") s"
p="$work/mocap_out/proposals.json"
jq -r '"prop1 \(.proposals[0].objective)", (.compared[] | "\(.rig) \(.objective)")' "$p"
jq -e '([.compared[] | select(.rig | startswith("gen_")) | .objective] | max) as $gen
       | ([.compared[] | select(.rig == "corners") | .objective][0]) as $corners
       | .proposals[0].objective >= $gen + 0.05 and .proposals[0].objective >= $corners' "$p" > /dev/null \
  || fail "mocap: the proposal is not 5 points above the generators and at least the corners rig"
t="$examples/trauma_room/scene.json"
"$pandora" propose "$t" --cameras 8 --objective coverage2 --points 1000 --mounts none \
  --mount-box=-1.5,-1.5,1.6,2.5,1.5,2.4 --spacing 0.25 --iterations 100000 --compare grid4x2 \
  --out "$work/trauma_out" -q || fail "propose trauma"
q="$work/trauma_out/proposals.json"
jq -r '"prop1 \(.proposals[0].objective)", (.compared[] | "\(.rig) \(.objective)")' "$q"
jq -e '.proposals[0].objective >= .compared[0].objective' "$q" > /dev/null || fail "trauma: below grid4x2"
echo "ok: proposals beat the generators and match or beat the hand-made rigs"
