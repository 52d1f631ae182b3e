#!/usr/bin/env bash
# Every analysis streams (docs/scale.md): for every rig of SCENE, with the fields and the analyses
# its file asks for (N-1 from the "cameras" field, pixel-size targets, DORI, named regions, people
# over time and surface targets, calibration, PTZ reach and tours), `pandora analyze --stream`
# at VOXEL_SIZE metres with tiles of TILE_SIZE metres, and (when MPI is built, the last argument "mpi") the same under
# `mpirun -n 2 ... --stream --mpi`, give the in-memory run's grids voxel for voxel (the union of the
# tiles: fields, coverage_n1, pixels_*, coverage_min, coverage_time_share, ptz_*) and its
# summary.json but for timings (tests/cli/same_fields.py). Each run under `timeout`: a hang fails.
# Usage: check_stream_analyses.sh PANDORA PYTHON SCENE WORK_DIR TILE_SIZE VOXEL_SIZE [mpi]
set -u
pandora=$1; python=$2; scene=$3; work=$4; tile=$5; voxel=$6; with_mpi=${7:-}
here=$(cd "$(dirname "$0")" && pwd)
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$work"; mkdir -p "$work"
rigs=$(jq -r '.rigs[].name' "$scene") || fail "cannot read the rigs of $scene"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
for rig in $rigs; do
  out=$work/$rig
  timeout 300 "$pandora" analyze "$scene" --rig "$rig" --voxel-size "$voxel" --out "$out/memory" --quiet \
    || fail "$rig: in-memory analyze exit $?"
  timeout 300 "$pandora" analyze "$scene" --rig "$rig" --voxel-size "$voxel" --out "$out/stream" --stream --tile-size "$tile" \
    --quiet || fail "$rig: --stream exit $?"
  runs=stream
  if [ "$with_mpi" = mpi ] && command -v mpirun > /dev/null; then
    timeout 300 mpirun -n 2 "$pandora" analyze "$scene" --rig "$rig" --voxel-size "$voxel" --out "$out/mpi" --stream \
      --tile-size "$tile" --mpi --threads 1 --quiet > "$out/mpi.log" 2>&1 \
      || fail "$rig: mpirun -n 2 --stream --mpi exit $?: $(tail -3 "$out/mpi.log")"
    runs="$runs mpi"
  fi
  for run in $runs; do
    "$python" "$here/same_fields.py" "$out/memory" "$out/$run" || fail "$rig: $run differs from in-memory"
  done
  # Not vacuous: several tiles, and every analysis the scene asks for is in the summary.
  jq -e --slurpfile scene "$scene" '
    ($scene[0].study) as $study
    | .stream.tile_count > 1
      and ((($study.fields // []) | index("cameras")) == null
           or ((.robustness.per_camera | length) > 0 and .robustness.seconds > 0))
      and (($study.pixel_targets // []) | length) == (.pixel_targets | length)
      and (($scene[0].motions // null) == null or (.time.samples | length) > 1)
      and ((.per_camera | map(select(.enabled)) | length) > 0)' "$out/stream/summary.json" > /dev/null \
    || fail "$rig: the streamed summary lacks an analysis the scene asks for"
  if jq -e --arg rig "$rig" '.rigs[] | select(.name == $rig) | .cameras | any(has("ptz"))' "$scene" > /dev/null; then
    jq -e '(.ptz.cameras | length) > 0' "$out/stream/summary.json" > /dev/null || fail "$rig: no PTZ block"
  fi
done
echo "ok: every analysis of $(basename "$(dirname "$scene")") streams equal to the in-memory run ($(echo $rigs))"
