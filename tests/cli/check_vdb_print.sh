#!/usr/bin/env bash
# Runs `pandora analyze` on a scene and checks that `vdb_print -l` lists the named grids and the
# metadata (units, tool version, scene hash, rig), and that summary.json has the required keys.
# Usage: check_vdb_print.sh PANDORA SCENE OUT_DIR
set -eu
pandora=$1; scene=$2; out=$3
rm -rf "$out"
"$pandora" analyze "$scene" --out "$out" --quiet
command -v vdb_print >/dev/null || { echo "FAIL: vdb_print not installed (libopenvdb-tools)"; exit 1; }
listing=$(vdb_print -l "$out/fields.vdb")
for want in "coverage" "cameras" "resolution" "units" "tool_version" "scene_sha256" "rig" "voxel_size_m"; do
  printf '%s\n' "$listing" | grep -q "$want" || { echo "FAIL: vdb_print -l lacks '$want'"; printf '%s\n' "$listing"; exit 1; }
done
sha=$(sha256sum "$scene" | cut -d' ' -f1)
printf '%s\n' "$listing" | grep -q "$sha" || { echo "FAIL: scene hash $sha not in metadata"; exit 1; }
for key in '"rig"' '"cameras"' '"voxel_size_m"' '"region_voxels"' '"active_voxels"' '"coverage"' \
           '"ge1"' '"ge2"' '"ge3"' '"per_camera"' '"visible_fraction"' '"timing"' '"seconds"' \
           '"rays"' '"rays_per_second"'; do
  grep -q "$key" "$out/summary.json" || { echo "FAIL: summary.json lacks $key"; exit 1; }
done
[ -z "$(ls "$out" | grep -F .tmp)" ] || { echo "FAIL: temporary files left: $(ls "$out")"; exit 1; }
echo "ok: vdb_print lists grids and metadata; summary.json has the keys"
