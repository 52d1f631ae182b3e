#!/usr/bin/env bash
# Calibration feasibility on the command line (docs/calibration.md): tests/data/minimal.json with a
# wand calibration and a third camera looking away from the region. analyze prints the lines and
# writes summary.json's "calibration" (the two cameras one component, "away" uncalibratable, the
# matrix symmetric with its diagonal equal to the per-camera counts); report has the Calibration
# section with one heat map per rig; a bad calibration key is the one-line error with exit code 2.
# Usage: check_calibration.sh PANDORA MINIMAL_JSON WORK_DIR
set -u
pandora=$1; minimal=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
scene="$work/scene.json"
jq '.rigs[0].cameras += [
      {"id": "away", "position": [0, -2, 1], "look_at": [0, -4, 1], "resolution": [64, 48], "hfov_deg": 60}]
    | .study.calibration = {"target": "wand", "samples": 300, "seed": 5, "min_shared": 10}' \
  "$minimal" >"$scene"

"$pandora" analyze "$scene" --out "$work/a" >"$work/a.out" 2>/dev/null || fail "analyze exit code $?"
grep -q '^calibration (wand): 300 poses' "$work/a.out" || fail "no calibration line: $(cat "$work/a.out")"
grep -q '^  uncalibratable: away$' "$work/a.out" || fail "no uncalibratable line: $(cat "$work/a.out")"
s="$work/a/summary.json"
[ "$(jq -c '.calibration.components' "$s")" = '[["a","b"],["away"]]' ] || fail "components $(jq -c .calibration.components "$s")"
[ "$(jq -c '.calibration.uncalibratable' "$s")" = '["away"]' ] || fail "uncalibratable"
[ "$(jq '.calibration.poses' "$s")" -eq 300 ] || fail "poses"
[ "$(jq '.calibration.per_camera[2].observed' "$s")" -eq 0 ] || fail "away observes something"
[ "$(jq '[.calibration.shared as $m | range(3) as $i | range(3) as $j | $m[$i][$j] == $m[$j][$i]] | all' "$s")" = true ] ||
  fail "matrix not symmetric"
[ "$(jq '[.calibration.per_camera[] | .observed] == [range(3) as $i | .calibration.shared[$i][$i]]' "$s")" = true ] ||
  fail "diagonal differs from the per-camera counts"
[ "$(jq '.calibration.weakest_links | length' "$s")" -eq 1 ] || fail "weakest links"

"$pandora" report "$scene" --out "$work/r" --width 64 --camera-width 32 -q || fail "report exit code $?"
html="$work/r/report.html"
grep -q '<h2 id="calibration">Calibration</h2>' "$html" || fail "no calibration section"
grep -q 'alt="pair calibration co-visibility matrix"' "$html" || fail "no heat map"

# suggest --objective calibration turns "away" back until it links to the rest (the suggestion
# file's "after" says so); without the study's calibration the objective is a one-line error.
"$pandora" suggest "$scene" --cameras away --max-move 0 --max-rotate 170 --objective calibration \
  --points 200 --out "$work/s.json" -q || fail "suggest exit code $?"
[ "$(jq '.improved' "$work/s.json")" = true ] || fail "calibration suggestion did not improve"
[ "$(jq '.metrics.before.calibration.uncalibratable' "$work/s.json")" -eq 1 ] || fail "before: $(jq -c .metrics.before "$work/s.json")"
[ "$(jq '.metrics.after.calibration.uncalibratable' "$work/s.json")" -eq 0 ] || fail "after: $(jq -c .metrics.after "$work/s.json")"
[ "$(jq '.metrics.after.calibration.weakest_shared >= 10' "$work/s.json")" = true ] || fail "weakest link"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/nocal" '$.study.calibration' -- \
  suggest "$minimal" --cameras a --objective calibration --out "$work/nocal/s.json" >/dev/null ||
  fail "calibration objective without study.calibration"

jq '.study.calibration.board = {"squares": [7, 5]}' "$scene" >"$work/bad.json"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/bad_out" '$.study.calibration.board' -- \
  analyze "$work/bad.json" --out "$work/bad_out" >/dev/null || fail "bad calibration key"
echo "ok"
