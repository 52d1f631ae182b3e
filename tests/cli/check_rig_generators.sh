#!/usr/bin/env bash
# `pandora rig` (docs/rig-generators.md) on a copy of examples/ptz_home: a ring, cameras along two
# walls and a ceiling grid are written into the scene file (a backup each time, the file's other
# rigs untouched), analyze runs on them; a name in use is refused unless --replace; --dry-run writes
# nothing; a scene in centimetres gets its positions in centimetres; bad layouts are one-line errors
# with exit code 2 that leave the file as it was. A generated rig renders as a plan and an elevation.
# Usage: check_rig_generators.sh PANDORA SCENE WORK_DIR
set -u
pandora=$1; scene=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
cp "$scene" "$work/s.json"
"$pandora" rig "$work/s.json" --name ring8 --ring 8 --radius 2.2 --height 2.3 --hfov 70 -q || fail "ring"
[ -f "$work/s.json.bak" ] || fail "no backup"
cmp -s "$work/s.json.bak" "$scene" || fail "the backup is not the original"
jq -e '[.rigs[] | select(.name == "ring8") | .cameras[]] | length == 8' "$work/s.json" >/dev/null || fail "ring8 has not 8 cameras"
# Every ring camera 2.2 m from the region's centre (0, 0), at 2.3 m.
jq -e '[.rigs[] | select(.name == "ring8") | .cameras[] | .position | ((.[0]*.[0] + .[1]*.[1]) | sqrt) - 2.2 | fabs] | max < 1e-9' \
  "$work/s.json" >/dev/null || fail "ring radius"
[ "$(jq -c '[.rigs[] | select(.name != "ring8")]' "$work/s.json")" = "$(jq -c '.rigs' "$scene")" ] || fail "other rigs changed"
"$pandora" rig "$work/s.json" --name walls --along=-2.9,-2.4,2.9,-2.4,2.9,2.4 --count 6 --height 2.4 -q || fail "along"
"$pandora" rig "$work/s.json" --name ceiling --grid 3,2 --rect=-2.5,-2,2.5,2 --height 2.5 --hfov 90 -q || fail "grid"
"$pandora" rig "$work/s.json" --name wallgrid --wall-grid 3,2 --wall=-2.9,2.4,2.9,2.4 --z-range 1,2.4 -q || fail "wall grid"
for r in ring8 walls ceiling wallgrid; do
  "$pandora" analyze "$work/s.json" --rig $r --voxel-size 0.25 --out "$work/an_$r" -q || fail "analyze $r"
  jq -e '.coverage.ge1 > 0.3' "$work/an_$r/summary.json" >/dev/null || fail "$r sees little: $(jq -c .coverage "$work/an_$r/summary.json")"
done
before=$(sha256sum < "$work/s.json")
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/e1" "already has a rig 'ring8'" -- \
  rig "$work/s.json" --name ring8 --ring 4 --radius 1 --height 2 >/dev/null || fail "name in use"
"$pandora" rig "$work/s.json" --name ring8 --replace --ring 4 --radius 1 --height 2 --dry-run > "$work/dry.json" || fail "dry run"
[ "$(sha256sum < "$work/s.json")" = "$before" ] || fail "an error or a dry run changed the file"
jq -e '[.rigs[] | select(.name == "ring8") | .cameras[]] | length == 4' "$work/dry.json" >/dev/null || fail "dry run output"
"$pandora" rig "$work/s.json" --name ring8 --replace --ring 4 --radius 1 --height 2 -q || fail "replace"
jq -e '[.rigs[] | select(.name == "ring8")] | length == 1 and (.[0].cameras | length) == 4' "$work/s.json" >/dev/null || fail "replaced"
# Centimetres: the positions in the file's unit.
jq '.units = "cm" | .objects = [] | .study.region.box = {"min": [-300, -250, 0], "max": [300, 250, 220]} | .study.voxel_size = 20 | del(.study.regions) | del(.study.pixel_targets) | del(.study.ptz) | .rigs = [.rigs[1]] | .rigs[0].cameras[0].position = [0, -230, 245] | .rigs[0].cameras[0].look_at = [0, 250, 150]' \
  "$scene" > "$work/cm.json"
"$pandora" rig "$work/cm.json" --name r --ring 4 --radius 2 --height 2 -q || fail "ring in cm"
jq -e '.rigs[-1].cameras[0].position == [200, 0, 200]' "$work/cm.json" >/dev/null || fail "cm positions: $(jq -c '.rigs[-1].cameras[0]' "$work/cm.json")"
# The proposal views of a generated rig: a plan and an elevation, labelled, with their scale.
"$pandora" render "$work/s.json" --rig walls --plan --size 400x300 --out "$work/plan.png" > "$work/plan.txt" || fail "plan"
grep -q "plan: 1 px = " "$work/plan.txt" || fail "plan scale: $(cat "$work/plan.txt")"
"$pandora" render "$work/s.json" --rig walls --elevation south --cut -1 --size 400x300 --out "$work/south.png" -q || fail "elevation"
[ -s "$work/plan.png" ] && [ -s "$work/south.png" ] || fail "no plan pictures"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/e9" "unknown side 'up'" -- \
  render "$work/s.json" --rig walls --elevation up --out "$work/e9/x.png" >/dev/null || fail "bad side"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/e10" "--cut" -- \
  render "$work/s.json" --rig walls --view overview --cut 1 --out "$work/e10/x.png" >/dev/null || fail "--cut without a plan"
err() { bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/e$1" "$2" -- "${@:3}" >/dev/null || fail "error $1 ($2)"; }
err 2 "give one layout" rig "$work/s.json" --name x --ring 4 --grid 2,2 --radius 1 --height 2
err 3 "which layout" rig "$work/s.json" --name x
err 4 "whole number" rig "$work/s.json" --name x --ring 0 --radius 1 --height 2
err 5 "X0 < X1" rig "$work/s.json" --name x --grid 2,2 --rect 1,1,0,0 --height 2
err 6 "has no length" rig "$work/s.json" --name x --along 1,1,1,1 --count 3 --height 2
err 7 "needs its radius" rig "$work/s.json" --name x --ring 3 --height 2
err 8 "on the point" rig "$work/s.json" --name x --grid 1,1 --rect=-1,-1,1,1 --height 1 --aim 0,0,1
# Several layouts into one rig (--add): the ids continue; a catalogue model's lens; PTZ heads.
catalogue="$(dirname "$0")/../../examples/lab_from_room/cameras.json"
"$pandora" rig "$work/s.json" --name mixed --ring 3 --radius 1 --height 2 -q || fail "mixed ring"
"$pandora" rig "$work/s.json" --name mixed --add --grid 2,1 --rect=-1,-1,1,1 --height 2.3 \
  --catalogue "$catalogue" --model zoom-4MP --ptz zoom -q || fail "--add"
jq -e '[.rigs[] | select(.name == "mixed") | .cameras[] | .id] == ["mixed_1", "mixed_2", "mixed_3", "mixed_4", "mixed_5"]' "$work/s.json" >/dev/null || fail "--add ids"
jq -e '[.rigs[] | select(.name == "mixed") | .cameras[3] | .resolution == [2688, 1520] and .distortion.model == "brown_conrady" and .ptz.zoom_hfov_deg[0] == .hfov_deg and .ptz.zoom_hfov_deg[1] < 30] | all' "$work/s.json" >/dev/null || fail "catalogue + ptz"
"$pandora" analyze "$work/s.json" --rig mixed --out "$work/mixed" --quiet || fail "analyze mixed"
"$pandora" rig "$work/s.json" --name ptz2 --ring 2 --radius 1 --height 2 --hfov 60 --ptz 60,10 -q || fail "--ptz"
jq -e '[.rigs[] | select(.name == "ptz2") | .cameras[].ptz.zoom_hfov_deg] == [[60, 10], [60, 10]]' "$work/s.json" >/dev/null || fail "ptz block"
err 9 "not both" rig "$work/s.json" --name mixed --add --replace --ring 2 --radius 1 --height 2
err 10 "no model 'nope'" rig "$work/s.json" --name y --ring 2 --radius 1 --height 2 --catalogue "$catalogue" --model nope
err 11 "WIDEST,NARROWEST" rig "$work/s.json" --name y --ring 2 --radius 1 --height 2 --hfov 60 --ptz 50,10
err 12 "no zoom range" rig "$work/s.json" --name y --ring 2 --radius 1 --height 2 --catalogue "$catalogue" --model mocap-3MP --ptz zoom
echo "ok"
