#!/usr/bin/env bash
# `pandora analyze --mpi` (docs/scale.md): on SCENE, mpirun with 2 and 4 ranks (one thread each,
# oversubscribed on a small machine) writes fields.vdb and summary.json equal to the single-process
# run voxel for voxel (tests/cli/same_fields.py; summaries but for timings), the summary's mpi block
# lists every rank, and a bad --out under mpirun prints one error line, exits 2 and writes nothing.
# Usage: check_mpi.sh PANDORA PYTHON SCENE WORK_DIR [RIG]
set -u
pandora=$1; python=$2; scene=$3; work=$4; rig=${5:-}
here=$(cd "$(dirname "$0")" && pwd)
fail() { echo "FAIL: $*"; exit 1; }
command -v mpirun >/dev/null || { echo "mpirun not installed (scripts/setup.sh installs openmpi-bin)"; exit 77; }
rm -rf "$work"; mkdir -p "$work"
# OpenMPI refuses root unless told; CI machines run as root.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
rigarg=(); [ -n "$rig" ] && rigarg=(--rig "$rig")
"$pandora" analyze "$scene" "${rigarg[@]}" --out "$work/single" --quiet || fail "single-process analyze exit $?"
for n in 2 4; do
  mpirun -n $n "$pandora" analyze "$scene" "${rigarg[@]}" --out "$work/n$n" --mpi --threads 1 --quiet \
    > "$work/n$n.log" 2>&1 || fail "mpirun -n $n exit $?: $(tail -5 "$work/n$n.log")"
  "$python" "$here/same_fields.py" "$work/single" "$work/n$n" || fail "$n ranks differ from one process"
  "$python" - "$work/n$n/summary.json" $n <<'PY' || fail "summary mpi block"
import json, sys
s = json.load(open(sys.argv[1])); n = int(sys.argv[2])
m = s["mpi"]
assert m["ranks"] == n and len(m["per_rank"]) == n, m
assert sum(r["rays"] for r in m["per_rank"]) == s["timing"]["rays"], m
# The static balance: no rank holds more than 4/3 of an even share of the (voxel, camera) pairs
# (plus one block's worth).
tests = [r["point_camera_tests"] for r in m["per_rank"]]
assert max(tests) <= 4 / 3 * sum(tests) / n + 512 * 64, tests
PY
done
# A bad output folder: one error line (rank 0's), exit 2 from mpirun, nothing written.
err=$(mpirun -n 2 "$pandora" analyze "$scene" "${rigarg[@]}" --out /proc/pandora_cannot_write_here --mpi --threads 1 2>&1 >/dev/null)
code=$?
[ "$code" -ne 0 ] || fail "unwritable --out under mpirun exited 0"
[ "$(printf '%s\n' "$err" | grep -c '^pandora: error:')" -eq 1 ] || fail "expected one error line, got: $err"
# An input error on one rank only (rank 1 reads a damaged copy of the scene; rank 0 a good one, as
# MPMD): every rank ends, mpirun exits non-zero within the timeout, rank 0 prints the one line
# naming rank 1, and nothing is written. It once left rank 0 waiting for ever.
head -c 200 "$scene" > "$work/damaged.json"
modes=(memory)
# Streamed too where the scene streams (one with moving people is refused by rank 0 itself).
"$pandora" analyze "$scene" "${rigarg[@]}" --stream --fields coverage --out "$work/stream_check" --quiet 2> /dev/null &&
  modes+=(stream)
for mode in "${modes[@]}"; do
  extra=(); [ $mode = stream ] && extra=(--stream --fields coverage)
  err=$(timeout 120 mpirun -n 1 "$pandora" analyze "$scene" "${rigarg[@]}" "${extra[@]}" --out "$work/rank1_$mode" --mpi --threads 1 : \
        -n 1 "$pandora" analyze "$work/damaged.json" "${rigarg[@]}" "${extra[@]}" --out "$work/rank1_$mode" --mpi --threads 1 2>&1 >/dev/null)
  code=$?
  [ "$code" -ne 124 ] || fail "$mode: an error on rank 1 alone left the run hanging"
  [ "$code" -ne 0 ] || fail "$mode: an error on rank 1 alone exited 0"
  [ "$(printf '%s\n' "$err" | grep -c '^pandora: error:')" -eq 1 ] || fail "$mode: expected one error line, got: $err"
  printf '%s\n' "$err" | grep -q 'on MPI rank 1' || fail "$mode: the line does not name rank 1: $err"
  [ ! -e "$work/rank1_$mode/summary.json" ] || fail "$mode: a summary was written"
done
echo "mpi: 2 and 4 ranks equal one process"
