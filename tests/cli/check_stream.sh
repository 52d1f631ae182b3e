#!/usr/bin/env bash
# `pandora analyze --stream` (docs/scale.md): the region evaluated and written tile by tile gives the
# in-memory run's fields voxel for voxel (the union of the tiles, no voxel in two) and its summary
# but for timings, with tiles of a given side and with tiles sized by a small memory budget; every
# tile listed in the summary exists and says which part of the lattice it holds; options that do
# not go together are refused with one line and exit 2, writing nothing; DORI classes and named
# sub-regions stream too (every other analysis: check_stream_analyses.sh).
# With MPI (the last argument "mpi"), `mpirun -n 2 ... --stream --mpi` gives the same files.
# Usage: check_stream.sh PANDORA PYTHON SCENE WORK_DIR FIELDS TILE_SIZE BUDGET_MIB [mpi]
set -u
pandora=$1; python=$2; scene=$3; work=$4; fields=$5; tile=$6; budget=$7; with_mpi=${8:-}
here=$(cd "$(dirname "$0")" && pwd)
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$work"; mkdir -p "$work"
"$pandora" analyze "$scene" --fields "$fields" --out "$work/memory" --quiet || fail "in-memory analyze exit $?"
"$pandora" analyze "$scene" --fields "$fields" --out "$work/sized" --stream --tile-size "$tile" --quiet \
  || fail "--stream --tile-size exit $?"
"$pandora" analyze "$scene" --fields "$fields" --out "$work/budget" --stream --memory-budget "$budget" --quiet \
  || fail "--stream --memory-budget exit $?"
runs="sized budget"
# Under mpirun (when installed): two processes share the tiles, each writes its own; the same files.
if [ "$with_mpi" = mpi ] && command -v mpirun >/dev/null; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
  mpirun -n 2 "$pandora" analyze "$scene" --fields "$fields" --out "$work/mpi" --stream --tile-size "$tile" \
    --mpi --threads 1 --quiet > "$work/mpi.log" 2>&1 || fail "mpirun -n 2 --stream exit $?: $(tail -5 "$work/mpi.log")"
  runs="$runs mpi"
fi
for run in $runs; do
  [ ! -e "$work/$run/fields.vdb" ] || fail "$run: a streamed run wrote fields.vdb"
  "$python" "$here/same_fields.py" "$work/memory" "$work/$run" || fail "$run: streamed differs from in-memory"
  "$python" - "$work/$run" <<'PY' || fail "$run: tiles"
import json, os, sys
import pyopenvdb as vdb
folder = sys.argv[1]
s = json.load(open(f"{folder}/summary.json"))
st = s["stream"]
tiles = st["tiles"]
assert st["tile_count"] == len(tiles) > 1, st["tile_count"]
assert sorted(os.listdir(f"{folder}/fields")) == sorted(os.path.basename(t["file"]) for t in tiles)
assert sum(t["region_voxels"] for t in tiles) == s["region_voxels"]
assert sum(t["seen_voxels"] for t in tiles) == s["active_voxels"]
if folder.endswith("budget"):  # tiles sized by the budget: each estimate within half of it
    assert st["largest_tile_estimate_mib"] <= st["memory_budget_mib"] / 2, st
if folder.endswith("mpi"):  # both processes wrote tiles
    assert st["ranks"] == 2 and sorted({t["rank"] for t in tiles}) == [0, 1], st
for i, t in enumerate(tiles):
    meta = vdb.readAllGridMetadata(f"{folder}/{t['file']}")[0]
    assert meta["tile"] == f"{i} of {len(tiles)}", meta["tile"]
    assert meta["tile_voxel_min"] == ",".join(map(str, t["voxel_min"])), meta
    assert meta["run_id"] == s["run_id"]
PY
done
# Refused: options that do not go together, and damaged values. One line, exit 2, nothing written.
expect_refusal() {
  local what=$1; shift
  local err code
  err=$("$pandora" analyze "$scene" --out "$work/refused" "$@" 2>&1 >/dev/null); code=$?
  [ "$code" -eq 2 ] || fail "$what: exit $code, expected 2 ($err)"
  [ "$(printf '%s\n' "$err" | wc -l)" -eq 1 ] || fail "$what: expected one line, got: $err"
  printf '%s\n' "$err" | grep -q -- "$what" || fail "expected '$what' in: $err"
  [ ! -e "$work/refused" ] || fail "$what: wrote $work/refused"
}
expect_refusal "--fields" --stream --fields coverage,no_such_field
expect_refusal "--tile-size" --tile-size 1
expect_refusal "--tile-size" --stream --tile-size -1 --fields coverage
expect_refusal "tiles, over 10000" --stream --tile-size 1e-9 --voxel-size 0.0002 --fields coverage
# DORI classes and named sub-regions stream: each tile holds its part of the "dori" grid, the
# shares add up exactly, the regions' percentiles come from the spilled values. Two regions: one
# box around the region's middle, one the region's lower half (numbers from the scene's region).
"$python" - "$scene" "$work/with_dori.json" <<'PY' || fail "writing the DORI scene"
import json, sys
s = json.load(open(sys.argv[1]))
box = s["study"]["region"]["box"]
lo, hi = box["min"], box["max"]
mid = [(a + b) / 2 for a, b in zip(lo, hi)]
quarter = [(b - a) / 4 for a, b in zip(lo, hi)]
s["study"]["dori"] = True
s["study"]["regions"] = {
    "middle": {"box": {"min": [m - q for m, q in zip(mid, quarter)], "max": [m + q for m, q in zip(mid, quarter)]}},
    "lower": {"box": {"min": lo, "max": [hi[0], hi[1], mid[2]]}},
}
json.dump(s, open(sys.argv[2], "w"))
PY
"$pandora" analyze "$work/with_dori.json" --fields coverage,resolution,sigma_max --out "$work/dori_memory" --quiet || fail "DORI in memory"
"$pandora" analyze "$work/with_dori.json" --fields coverage,resolution,sigma_max --out "$work/dori_stream" --stream \
  --tile-size "$tile" --quiet || fail "DORI streamed"
"$python" "$here/same_fields.py" "$work/dori_memory" "$work/dori_stream" || fail "DORI: streamed differs from in-memory"
if [ "$with_mpi" = mpi ] && command -v mpirun >/dev/null; then
  mpirun -n 2 "$pandora" analyze "$work/with_dori.json" --fields coverage,resolution,sigma_max --out "$work/dori_mpi" \
    --stream --tile-size "$tile" --mpi --threads 1 --quiet > "$work/dori_mpi.log" 2>&1 \
    || fail "DORI under mpirun exit $?: $(tail -5 "$work/dori_mpi.log")"
  "$python" "$here/same_fields.py" "$work/dori_memory" "$work/dori_mpi" || fail "DORI: mpirun differs from in-memory"
fi
"$python" -c "
import json, sys
s = json.load(open(sys.argv[1]))
assert 0 < s['dori']['detection'] <= 1, s['dori']
assert sorted(r['name'] for r in s['regions']) == ['lower', 'middle'] and all(r['voxels'] > 0 for r in s['regions']), s['regions']
assert all(r['sigma_max_p50_mm'] is not None and r['resolution_p10_px_per_m'] is not None for r in s['regions']), s['regions']
" "$work/dori_stream/summary.json" || fail "DORI and regions: shares and percentiles"
echo "stream: tiles equal the in-memory run"
