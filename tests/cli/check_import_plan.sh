#!/usr/bin/env bash
# `pandora import-plan` on the lab's floor plan (examples/lab_from_room/lab.dxf): the imported scene
# is the lab built from a `room` object, voxel for voxel (both analysed with the room scene's ring
# and study, people left out: the plan has none); --replace keeps a backup; bad input is one line
# and exit 2 with nothing written.
# Usage: check_import_plan.sh PANDORA PYTHON EXAMPLE_DIR WORK_DIR
set -u
pandora=$1; python=$2; example=$3; work=$4
here=$(cd "$(dirname "$0")" && pwd)
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$work"; mkdir -p "$work"
layers=(--furniture desks:0.75 --furniture chairs:0.9 --furniture cabinets:1.9 --furniture racks:2.0 --height 3)
"$pandora" import-plan "$example/lab.dxf" -o "$work/plan.json" "${layers[@]}" > "$work/log" || fail "import-plan exit $?"
cat "$work/log"
grep -q "1 door, 1 window, 4 furniture" "$work/log" || fail "counts"
# The imported file analyses as it is (its first rig).
"$pandora" analyze "$work/plan.json" --out "$work/start" --quiet || fail "analyze plan.json exit $?"
jq -e '.cameras == 4 and .coverage.ge1 > 0.5' "$work/start/summary.json" > /dev/null || fail "start rig"
# Equivalent to the room: same rig, same study, no people.
jq '.objects |= map(select(has("person") | not)) | del(.motions) | del(.study.targets) | del(.study.time)' \
  "$example/scene.json" > "$work/room.json"
jq --slurpfile r "$work/room.json" '.rigs = $r[0].rigs | .study = $r[0].study' "$work/plan.json" > "$work/plan_ring.json"
cp "$work/room.json" "$work/scene.json"; "$pandora" analyze "$work/scene.json" --out "$work/room_out" --quiet || fail "room"
cp "$work/plan_ring.json" "$work/scene.json"; "$pandora" analyze "$work/scene.json" --out "$work/plan_out" --quiet || fail "plan"
for d in room_out plan_out; do  # the two files differ in their text, not in what they analyse
  jq 'del(.scene_sha256)' "$work/$d/summary.json" > "$work/s.json" && mv "$work/s.json" "$work/$d/summary.json"
done
"$python" "$here/same_fields.py" "$work/room_out" "$work/plan_out" || fail "the plan differs from the room"
# An existing output: refused without --replace; replaced with a backup.
before=$(sha256sum "$work/plan.json" | cut -d' ' -f1)
bash "$here/expect_error.sh" "$pandora" "$work/none" "exists" -- import-plan "$example/lab.dxf" -o "$work/plan.json" || exit 1
test "$(sha256sum "$work/plan.json" | cut -d' ' -f1)" = "$before" || fail "overwritten without --replace"
"$pandora" import-plan "$example/lab.dxf" -o "$work/plan.json" --replace --height 2.5 -q || fail "--replace exit $?"
test "$(sha256sum "$work/plan.json.bak" | cut -d' ' -f1)" = "$before" || fail "no backup"
jq -e '[.objects[] | select(.name == "walls/2.1") | .box.size[2]] == [2.5]' "$work/plan.json" > /dev/null || fail "--height"
# Bad input.
printf '0\nSECTION\n2\nENTITIES\n0\nLINE\n8\nwalls\n10\n0\n20\n0\n11\n5\n21\n0\n0\nENDSEC\n0\nEOF\n' > "$work/nounit.dxf"
bash "$here/expect_error.sh" "$pandora" "$work/o1" "does not say its unit" -- import-plan "$work/nounit.dxf" -o "$work/o1/s.json" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o2" "the drawing's layers with lines: 'cabinets'" -- \
  import-plan "$example/lab.dxf" -o "$work/o2/s.json" --layer mauern || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o3" "holds no DXF entities" -- import-plan "$example/scene.json" -o "$work/o3/s.json" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o4" "LAYER:HEIGHT" -- import-plan "$example/lab.dxf" -o "$work/o4/s.json" --furniture desks:tall || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o5" "no such file" -- import-plan "$work/missing.dxf" -o "$work/o5/s.json" || exit 1
cp "$example/lab.dxf" "$work/self.dxf"
bash "$here/expect_error.sh" "$pandora" "$work/o6" "is the floor plan itself" -- import-plan "$work/self.dxf" -o "$work/self.dxf" --replace || exit 1
cmp -s "$example/lab.dxf" "$work/self.dxf" || fail "the plan was overwritten"
echo "ok: the lab's plan imports into the room, voxel for voxel"
