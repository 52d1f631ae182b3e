#!/usr/bin/env bash
# scripts/blender_scene.py (docs/tool-chain.md, "Blender"): the glTF of export-rig and a fields.vdb
# of analyze in Blender: every camera of the rig imported, the coverage grid shown with its material,
# the file saved and a small Cycles picture rendered from the first camera, not blank.
# Usage: check_scene_script.sh PANDORA BLENDER_COMMAND SCENE SCRIPT WORK_DIR
set -u
pandora=$1; blender=$2; scene=$3; script=$4; work=$5
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$work"; mkdir -p "$work"
"$pandora" export-rig "$scene" --format gltf --out "$work/scene.gltf" >/dev/null || fail "export-rig"
"$pandora" analyze "$scene" --out "$work" --quiet || fail "analyze"
cameras=$(jq '.rigs[0].cameras | length' "$scene")
$blender -b --factory-startup --python-exit-code 1 --python "$script" -- --gltf "$work/scene.gltf" \
  --vdb "$work/fields.vdb" --field coverage --save "$work/scene.blend" --render "$work/picture.png" \
  --size 96x60 --samples 2 > "$work/blender.txt" 2>&1 || fail "blender: $(grep -E 'FAIL|Error' "$work/blender.txt" | head -3)"
grep -q "glTF .*: [0-9]* meshes, $cameras cameras" "$work/blender.txt" || fail "not $cameras cameras: $(grep glTF "$work/blender.txt")"
grep -q "showing 'coverage'" "$work/blender.txt" || fail "no coverage volume"
grep -q "material pandora_coverage: viridis 0 .. 2" "$work/blender.txt" || fail "material: $(grep material "$work/blender.txt")"
[ -s "$work/scene.blend" ] || fail "no scene.blend"
[ -s "$work/picture.png" ] || fail "no picture"
echo "ok: Blender loaded the scene, its $cameras cameras and the fields"
