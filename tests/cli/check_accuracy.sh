#!/usr/bin/env bash
# Runs `pandora accuracy --quick` on a scene and checks its outputs: the CSV files and SVG plots
# exist (no temporary file left), the named columns hold finite numbers on every row, and the
# Monte Carlo relative error of sigma_max (mean over the sample points) at the largest trial count
# is below 10%; at least 95% of the Monte Carlo gate's voxels pass.
# Usage: check_accuracy.sh PANDORA SCENE OUT_DIR
set -eu
pandora=$1; scene=$2; out=$3
rm -rf "$out"; mkdir -p "$(dirname "$out")"
"$pandora" accuracy "$scene" --out "$out" --quick > "$out.log" 2>&1 || { echo "FAIL: pandora accuracy exited $?"; cat "$out.log"; exit 1; }
fail() { echo "FAIL: $*"; exit 1; }

for f in accuracy_voxel.csv accuracy_montecarlo.csv accuracy_steady.csv accuracy_gate.csv \
         accuracy_voxel.svg accuracy_montecarlo.svg accuracy_steady.svg accuracy_gate.svg \
         accuracy_tables.md; do
  [ -s "$out/$f" ] || fail "$f missing or empty"
  [ -z "$(ls "$out" | grep -F "$f.tmp")" ] || fail "$f.tmp* left behind"
done
for f in accuracy_voxel.svg accuracy_montecarlo.svg accuracy_steady.svg accuracy_gate.svg; do
  head -c 200 "$out/$f" | grep -q '<svg ' || fail "$f does not start an SVG document"
  tail -n 1 "$out/$f" | grep -q '</svg>' || fail "$f is not closed"
  if command -v xmllint >/dev/null; then xmllint --noout "$out/$f" || fail "$f is not well-formed XML"; fi
done

# check_columns FILE MIN_ROWS COLUMN...: every row has a finite number in each named column.
check_columns() {
  local file=$1 min_rows=$2; shift 2
  awk -F, -v cols="$*" -v min_rows="$min_rows" -v file="$file" '
    NR == 1 { for (i = 1; i <= NF; ++i) index_of[$i] = i
              n = split(cols, want, " ")
              for (k = 1; k <= n; ++k) if (!(want[k] in index_of)) { print "FAIL: " file " lacks column " want[k]; bad = 1 }
              next }
    { rows++
      for (k = 1; k <= n; ++k) { v = $(index_of[want[k]])
        if (v !~ /^-?[0-9]+(\.[0-9]*)?([eE][-+]?[0-9]+)?$/) { print "FAIL: " file " row " NR " column " want[k] " = \"" v "\" is not a finite number"; bad = 1 } } }
    END { if (rows < min_rows) { print "FAIL: " file " has " rows " rows, expected >= " min_rows; bad = 1 }
          exit bad }' "$out/$file"
}
check_columns accuracy_voxel.csv 3 voxel_size_m seconds time_ratio ge1 ge2 ge3 ge1_err_pp ge2_err_pp ge3_err_pp \
  sigma_max_p50_mm sigma_max_p90_mm sigma_max_p50_err_pct sigma_max_p90_err_pct
check_columns accuracy_montecarlo.csv 3 trials points seconds_per_point sigma_max_rel_err_mean_pct \
  sigma_max_rel_err_max_pct frobenius_rel_err_mean_pct frobenius_rel_err_max_pct failures \
  prediction_seconds_per_point time_ratio_to_prediction
check_columns accuracy_steady.csv 9 q_m2_s3 rate_hz iterations converged seconds_per_voxel rel_err

# The reference row (the finest size) has zero error; the Monte Carlo error at the largest N < 10%.
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
         $(c["reference"]) == 1 { ref = 1; if ($(c["ge1_err_pp"]) != 0 || $(c["sigma_max_p50_err_pct"]) != 0) bad = 1 }
         END { exit !(ref && !bad) }' "$out/accuracy_voxel.csv" || fail "voxel reference row missing or with nonzero error"
read -r trials rel frob failures < <(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
  $(c["trials"]) + 0 > best { best = $(c["trials"]) + 0
    line = $(c["trials"]) " " $(c["sigma_max_rel_err_mean_pct"]) " " $(c["frobenius_rel_err_mean_pct"]) " " $(c["failures"]) }
  END { print line }' "$out/accuracy_montecarlo.csv")
awk -v r="$rel" 'BEGIN { exit !(r < 10) }' || fail "Monte Carlo sigma_max error at N=$trials is $rel% (>= 10%)"
awk -v r="$frob" 'BEGIN { exit !(r < 10) }' || fail "Monte Carlo Frobenius error at N=$trials is $frob% (>= 10%)"
[ "$failures" = 0 ] || fail "$failures Monte Carlo trials failed at N=$trials"
# The closed form agrees with its long-double evaluation to round-off in every case.
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
         $(c["method"]) ~ /^closed form/ { n++; if (!($(c["rel_err"]) + 0 < 1e-13)) bad = 1 }
         END { exit !(n >= 3 && !bad) }' "$out/accuracy_steady.csv" || fail "closed form off its long-double reference"
# The Monte Carlo gate (f): voxels with finite predicted sigmas and ratios; >= 95% of them pass.
check_columns accuracy_gate.csv 2 x_m y_m z_m cameras predicted_major_mm ratio_major ratio_middle \
  ratio_minor skew_major failures pass
read -r voxels passed < <(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
  { n++; p += $(c["pass"]) } END { print n, p }' "$out/accuracy_gate.csv")
awk -v n="$voxels" -v p="$passed" 'BEGIN { exit !(p >= 0.95 * n) }' ||
  fail "Monte Carlo gate: $passed of $voxels voxels pass (< 95%)"
echo "ok: accuracy tables and plots written; Monte Carlo at N=$trials: sigma_max error $rel%, Frobenius $frob%"
