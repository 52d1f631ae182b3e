#!/usr/bin/env bash
# Runs `pandora analyze` on a scene and checks that `vdb_print -l` lists the named grids and the
# metadata (units, tool version, scene hash, rig), and that summary.json has the required keys.
# With a fourth argument "uncertainty", also the uncertainty grids and summary keys.
# Usage: check_vdb_print.sh PANDORA SCENE OUT_DIR [uncertainty]
set -eu
pandora=$1; scene=$2; out=$3; extra=${4:-}
rm -rf "$out"
"$pandora" analyze "$scene" --out "$out" --quiet
command -v vdb_print >/dev/null || { echo "FAIL: vdb_print not installed (libopenvdb-tools)"; exit 1; }
listing=$(vdb_print -l "$out/fields.vdb")
wants=("coverage" "cameras" "resolution" "units" "tool_version" "scene_sha256" "rig" "voxel_size_m")
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
echo "ok: vdb_print lists grids and metadata; summary.json has the keys"
