#!/usr/bin/env bash
# Features that share code paths, combined (docs/robustness.md, "Combinations"): motion x every
# field, motion x --disable, motion x PTZ, motion x --mpi, --stream x motion, --disable x --stream.
# Each command runs under `timeout` (a hang is a failure, not a stuck CI) and must end with exit 0
# and its outputs.
# usage: check_combinations.sh PANDORA MOVING_BOX_SCENE PTZ_SCENE OUT_DIR
set -uo pipefail
pandora=$1 moving=$2 ptz=$3 out=$4
rm -rf "$out"
mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
run() {  # run NAME ARGS...: must finish within 60 s with exit 0
  local name=$1
  shift
  timeout 60 "$pandora" "$@" > "$out/$name.log" 2>&1
  local rc=$?
  [ $rc -eq 124 ] && fail "$name: did not finish within 60 s: $*"
  [ $rc -eq 0 ] || fail "$name: exit $rc: $(tail -3 "$out/$name.log")"
}

# Motion x every field (the flagship example's hang: a moving box and sigma_max never finished).
for f in coverage cameras resolution sigma_max sigma_mean triangulation_angle condition; do
  fields=coverage,$f
  [ $f = coverage ] && fields=coverage
  run "motion_$f" analyze "$moving" --fields "$fields" --out "$out/motion_$f" --quiet
  jq -e '.time.samples | length == 1' "$out/motion_$f/summary.json" > /dev/null || fail "motion_$f: no time block"
done
# Every field at once, with the people's surface targets' path too (report adds sigma_max).
run motion_report report "$moving" --out "$out/motion_report" --quiet
test -s "$out/motion_report/report.html" || fail "motion_report: no report.html"

# Motion x --disable: the disabled camera is gone at every time sample.
run motion_disable analyze "$moving" --disable b --out "$out/motion_disable" --quiet
jq -e '.time.samples[0].ge2 == 0' "$out/motion_disable/summary.json" > /dev/null ||
  fail "motion_disable: a voxel seen by two cameras with one of two disabled"

# Motion x PTZ: a PTZ scene with a moving box added.
jq '.objects += [{"name": "cart", "box": {"size": [0.5, 0.5, 1.0]}, "position": [0, 0, 0.5], "solid": true}]
    | .motions = {"cart": {"keyframes": [{"t": 0}, {"t": 2, "move": [1, 0, 0]}]}}
    | .study.time = {"times": [0, 2]}' "$ptz" > "$out/ptz_motion.json"
# Mesh paths in the PTZ scene are relative to its folder.
cp -r "$(dirname "$ptz")"/. "$out/ptz_dir" 2>/dev/null
mv "$out/ptz_motion.json" "$out/ptz_dir/ptz_motion.json"
run ptz_motion analyze "$out/ptz_dir/ptz_motion.json" --out "$out/ptz_motion" --quiet
jq -e '(.time.samples | length == 2) and (.ptz != null)' "$out/ptz_motion/summary.json" > /dev/null ||
  fail "ptz_motion: the summary lacks its time or ptz block"

# --stream x motion: the fields over time tile by tile equal the in-memory run's.
run stream_motion analyze "$moving" --stream --tile-size 1 --out "$out/stream_motion" --quiet
run memory_motion analyze "$moving" --out "$out/memory_motion" --quiet
time_block() { jq -c '.time | del(.seconds, .parts_seconds) | .samples |= map(del(.seconds))' "$1"; }
a=$(time_block "$out/stream_motion/summary.json")
b=$(time_block "$out/memory_motion/summary.json")
[ "$a" = "$b" ] || fail "stream_motion: time $a differs from the in-memory $b"
# --stream x --disable: a streamed run without the disabled camera equals the in-memory one.
jq 'del(.motions) | del(.study.time)' "$moving" > "$out/still.json"
run stream_disable analyze "$out/still.json" --stream --disable a --fields coverage,sigma_max --out "$out/stream_disable" --quiet
run memory_disable analyze "$out/still.json" --disable a --fields coverage,sigma_max --out "$out/memory_disable" --quiet
a=$(jq -c '.coverage' "$out/stream_disable/summary.json")
b=$(jq -c '.coverage' "$out/memory_disable/summary.json")
[ "$a" = "$b" ] || fail "stream_disable: coverage $a differs from the in-memory $b"

# --mpi x motion: two ranks equal one process (rank 0 evaluates the time samples).
if command -v mpirun > /dev/null; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
  timeout 120 mpirun -n 2 "$pandora" analyze "$moving" --mpi --threads 1 --out "$out/mpi_motion" --quiet \
    > "$out/mpi_motion.log" 2>&1 || fail "mpi_motion: exit $?: $(tail -3 "$out/mpi_motion.log")"
  a=$(jq -c '[.coverage, .time.samples[0].ge2, .uncertainty.sigma_max_mm]' "$out/mpi_motion/summary.json")
  b=$(jq -c '[.coverage, .time.samples[0].ge2, .uncertainty.sigma_max_mm]' "$out/motion_sigma_max/summary.json")
  [ "$a" = "$b" ] || fail "mpi_motion: $a differs from one process $b"
fi
echo "ok: combinations finish and agree"
