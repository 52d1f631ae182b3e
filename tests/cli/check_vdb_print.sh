#!/usr/bin/env bash
# Runs `pandora analyze` on a scene and checks that `vdb_print -l` lists the grids of the layout in
# docs/fields.md (coverage a FloatGrid, one BoolGrid "visible/<id>" per camera with its camera_id and
# camera_index, no integer grids) and the metadata (units, tool version, scene hash, rig), and that
# summary.json has the required keys. With a fourth argument "uncertainty", also the uncertainty
# grids and summary keys.
# Usage: check_vdb_print.sh PANDORA SCENE OUT_DIR [uncertainty]
set -eu
pandora=$1; scene=$2; out=$3; extra=${4:-}
rm -rf "$out"
"$pandora" analyze "$scene" --out "$out" --quiet
command -v vdb_print >/dev/null || { echo "FAIL: vdb_print not installed (libopenvdb-tools)"; exit 1; }
listing=$(vdb_print -l "$out/fields.vdb")
# The grid called $1 has type $2.
grid_type() {
  printf '%s\n' "$listing" | awk -v name="Name: $1" '$0 == name { found = 1; next } found && /Type:/ { print $2; exit }'
}
# VisibilityGridName: bytes outside [A-Za-z0-9_.-] as %XX.
encode() {
  local s=$1 out='' c i
  LC_ALL=C
  for ((i = 0; i < ${#s}; i++)); do
    c=${s:i:1}
    case $c in [A-Za-z0-9_.-]) out+=$c ;; *) out+=$(printf '%%%02X' "'$c") ;; esac
  done
  printf '%s' "$out"
}
[ "$(grid_type coverage)" = Tree_float_5_4_3 ] || { echo "FAIL: coverage is not a FloatGrid: $(grid_type coverage)"; exit 1; }
[ "$(grid_type resolution)" = Tree_float_5_4_3 ] || { echo "FAIL: resolution is not a FloatGrid"; exit 1; }
if printf '%s\n' "$listing" | grep -q "Type: Tree_int"; then echo "FAIL: an integer grid (pyopenvdb cannot read it)"; exit 1; fi
index=0
while IFS= read -r id; do
  name="visible/$(encode "$id")"
  [ "$(grid_type "$name")" = Tree_bool_5_4_3 ] || { echo "FAIL: no BoolGrid '$name' for camera '$id'"; printf '%s\n' "$listing" | grep "Name:"; exit 1; }
  printf '%s\n' "$listing" | grep -qx "  camera_id: $id" || { echo "FAIL: no camera_id $id"; exit 1; }
  index=$((index + 1))
done < <(jq -r '.per_camera[].id' "$out/summary.json")
[ "$index" -gt 0 ] || { echo "FAIL: summary.json lists no camera"; exit 1; }
cameras=$(printf '%s\n' "$listing" | grep -c "Type: Tree_bool_5_4_3")
[ "$cameras" -eq "$index" ] || { echo "FAIL: $cameras BoolGrids for $index cameras"; exit 1; }
for ((c = 0; c < index; c++)); do
  printf '%s\n' "$listing" | grep -qx "  camera_index: $c" || { echo "FAIL: no camera_index $c"; exit 1; }
done
wants=("units" "tool_version" "scene_sha256" "rig" "voxel_size_m" "value_units: cameras" "value_units: px/m")
[ "$extra" = uncertainty ] && wants+=("Name: sigma_max" "Name: sigma_mean" "Name: triangulation_angle" "Name: condition" "Name: sigma_max_steady" "Name: sigma_mean_steady" "value_units: mm")
for want in "${wants[@]}"; do
  printf '%s\n' "$listing" | grep -q "$want" || { echo "FAIL: vdb_print -l lacks '$want'"; printf '%s\n' "$listing"; exit 1; }
done
sha=$(sha256sum "$scene" | cut -d' ' -f1)
printf '%s\n' "$listing" | grep -q "$sha" || { echo "FAIL: scene hash $sha not in metadata"; exit 1; }
keys=('"rig"' '"cameras"' '"voxel_size_m"' '"region_voxels"' '"active_voxels"' '"coverage"'
      '"ge1"' '"ge2"' '"ge3"' '"per_camera"' '"visible_fraction"' '"timing"' '"seconds"'
      '"rays"' '"rays_per_second"')
[ "$extra" = uncertainty ] && keys+=('"uncertainty"' '"triangulable"' '"sigma_max_mm"' '"p50"' '"p90"' '"p99"'
      '"meets_max_sigma"' '"sigma_max_steady_mm"' '"meets_max_sigma_steady"')
for key in "${keys[@]}"; do
  grep -q "$key" "$out/summary.json" || { echo "FAIL: summary.json lacks $key"; exit 1; }
done
[ -z "$(ls "$out" | grep -F .tmp)" ] || { echo "FAIL: temporary files left: $(ls "$out")"; exit 1; }
echo "ok: vdb_print lists $index camera grids, the field grids and metadata; summary.json has the keys"
