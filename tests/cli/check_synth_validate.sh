#!/usr/bin/env bash
# `pandora synth` and `pandora validate` on tests/data/markers.json (a marker, a ChArUco board and a
# checkerboard seen by a pinhole, a Brown-Conrady and a fisheye camera): every output written
# together (images, depth EXR, corners.csv, rig.yaml, the COLMAP model, synth.json), the corner
# table consistent with the scene (4 marker corners, 15 ChArUco and 24 checkerboard inner corners),
# every corner pixel inside its image; validate's tables with finite ratios and its pictures; bad
# input as one line and exit code 2 with nothing written; COLMAP (where installed) reads the model;
# validate --calibration's table (a row and a status per camera) and verdict; report --validate's
# section.
# Usage: check_synth_validate.sh PANDORA MARKERS_JSON WORK_DIR
set -u
pandora=$1; scene=$2; work=$3
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

out="$work/synth"
"$pandora" synth "$scene" --out "$out" --samples 2 --noise 1 --quiet || fail "synth exited $?"
for f in synth.json corners.csv rig.yaml colmap/cameras.txt colmap/images.txt colmap/points3D.txt \
         images/left.png images/mid.png images/right.png depth/left.exr depth/mid.exr depth/right.exr; do
  [ -s "$out/$f" ] || fail "$f missing or empty"
done
[ -z "$(find "$out" -name '*.tmp*' -o -name '.pandora-staging*')" ] || fail "staging files left"
[ "$(jq '.images | length' "$out/synth.json")" = 3 ] || fail "synth.json lists $(jq '.images | length' "$out/synth.json") images"
[ "$(jq '.corners' "$out/synth.json")" = 43 ] || fail "synth.json: $(jq '.corners' "$out/synth.json") corners, expected 4 + 15 + 24"
head -c 8 "$out/images/mid.png" | od -An -tx1 | grep -q "89 50 4e 47" || fail "mid.png is not a PNG"
# Corners: 43 distinct (fiducial, corner), each view's pixel inside its camera's image.
awk -F, 'NR > 1 { key[$1 "/" $3] = 1
                  if ($7 != "") { w = ($7 == "right") ? 1024 : 960; h = ($7 == "right") ? 768 : 720
                                  if ($8 < -0.5 || $9 < -0.5 || $8 > w - 0.5 || $9 > h - 0.5) bad = 1; views++ } }
         END { n = 0; for (k in key) n++; if (n != 43 || bad || views < 40) exit 1 }' "$out/corners.csv" ||
  fail "corners.csv: wrong corner count or a pixel outside its image"
# The model names the synthetic images.
grep -q " left.png$" "$out/colmap/images.txt" || fail "images.txt does not name left.png"
if command -v colmap >/dev/null; then
  colmap model_converter --input_path "$out/colmap" --output_path "$work/colmap_bin" --output_type BIN \
    >/dev/null 2>&1 || fail "COLMAP cannot read the model"
fi

val="$work/validate"
"$pandora" validate "$scene" --out "$val" --poses 10 --samples 2 --min-bin 10 --quiet || fail "validate exited $?"
for f in validation.md validation_bins.csv validation_points.csv validation.svg detections.png; do
  [ -s "$val/$f" ] || fail "$f missing or empty"
done
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
         $(c["by"]) == "all" { all = 1
           for (k = 0; k < 3; ++k) { v = $(c[k == 0 ? "ratio_major" : k == 1 ? "ratio_middle" : "ratio_minor"])
             if (!(v > 0.2 && v < 5)) bad = 1 }
           if ($(c["corners"]) < 20) bad = 1 }
         END { exit !(all && !bad) }' "$val/validation_bins.csv" || fail "validation_bins.csv: no plausible 'all' row"
grep -q "Verdict:" "$val/validation.md" || fail "validation.md has no verdict"

# The calibration study: a row per camera (the fisheye through cv::fisheye::calibrate), each with a
# status, the verdict line; its outputs only.
cal="$work/calibration"
"$pandora" validate "$scene" --calibration --out "$cal" --poses 30 --samples 2 --quiet ||
  fail "validate --calibration exited $?"
for f in calibration.md calibration_cameras.csv; do [ -s "$cal/$f" ] || fail "$f missing or empty"; done
[ ! -e "$cal/validation.md" ] || fail "validate --calibration wrote validation.md"
[ "$(tail -n +2 "$cal/calibration_cameras.csv" | wc -l)" = 3 ] || fail "calibration_cameras.csv: not 3 cameras"
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
         { if ($(c["status"]) == "") bad = 1; if ($(c["lens"]) == "fisheye") fish = 1 }
         END { exit !(fish && !bad) }' "$cal/calibration_cameras.csv" || fail "calibration_cameras.csv: a camera without status"
grep -q "The verdict holds" "$cal/calibration.md" || fail "calibration.md has no verdict"

# The report's "Predicted against measured" section (report --validate): a cell per rig with the
# verdict and the plot.
rep="$work/report"
"$pandora" report "$scene" --validate --validate-poses 10 --width 64 --camera-width 32 --out "$rep" --quiet ||
  fail "report --validate exited $?"
grep -q 'id="validation"' "$rep/report.html" || fail "report.html has no validation section"
grep -q "corners triangulated" "$rep/report.html" || fail "the validation section has no result"

# Bad input: one line, exit code 2, nothing written.
bash "$here/expect_error.sh" "$pandora" "$work/bad1" "--samples" -- synth "$scene" --out "$work/bad1" --samples 0 || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/bad2" "--time-sample" -- synth "$scene" --out "$work/bad2" --time-sample 2 || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/bad3" "--rig" -- validate "$scene" --rig nope --out "$work/bad3" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/bad4" "--cameras" -- synth "$scene" --cameras left,nope --out "$work/bad4" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/bad5" "--squares" -- validate "$scene" --calibration --squares 2,2 --out "$work/bad5" || exit 1
echo "ok: synth wrote 3 images and 43 corners; validate wrote its tables; the calibration study its table"
