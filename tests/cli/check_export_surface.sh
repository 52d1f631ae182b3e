#!/usr/bin/env bash
# Runs `pandora export-surface` on SCENE and checks the PLY: the header names every property, the
# record bytes match the vertex count (44 bytes each), no temporary file is left, a second run
# with the same seed writes the same bytes while another seed does not, and --all-surfaces adds
# the faces that face away from the region.
# Usage: check_export_surface.sh PANDORA SCENE OUT_DIR
set -euo pipefail
pandora=$1; scene=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
"$pandora" export-surface "$scene" --spacing 0.02 --out "$out/a.ply" --quiet
"$pandora" export-surface "$scene" --spacing 0.02 --out "$out/b.ply" --quiet
"$pandora" export-surface "$scene" --spacing 0.02 --seed 2 --out "$out/c.ply" --quiet
fail() { echo "FAIL: $*"; exit 1; }
header=$(head -c 4096 "$out/a.ply" | sed -n '1,/^end_header$/p')
header_bytes=$(printf '%s\n' "$header" | wc -c)
[ "$(printf '%s\n' "$header" | sed -n 2p)" = "format binary_little_endian 1.0" ] || fail "format line"
for p in "float x" "float y" "float z" "float nx" "float ny" "float nz" "uchar red" "uchar green" \
         "uchar blue" "float coverage" "float resolution" "float sigma_max" "uchar triangulable" "int object"; do
  grep -qx "property $p" <<<"$header" || fail "no 'property $p' in the header"
done
count=$(printf '%s\n' "$header" | sed -n 's/^element vertex \([0-9]*\)$/\1/p')
[ -n "$count" ] && [ "$count" -gt 1000 ] || fail "vertex count '$count'"
size=$(stat -c %s "$out/a.ply")
[ "$size" -eq $((header_bytes + 44 * count)) ] || fail "size $size != $header_bytes + 44 * $count"
cmp -s "$out/a.ply" "$out/b.ply" || fail "same seed, different files"
cmp -s "$out/a.ply" "$out/c.ply" && fail "different seeds, same file"
# --all-surfaces adds the faces neither the region nor a camera faces (for the minimal scene's block
# standing on the region's floor z = 0, cameras above: its bottom, one face of six, so about 6/5 of
# the samples).
"$pandora" export-surface "$scene" --spacing 0.02 --all-surfaces --out "$out/all.ply" --quiet
all=$(head -c 4096 "$out/all.ply" | sed -n 's/^element vertex \([0-9]*\)$/\1/p')
[ "$all" -gt "$count" ] || fail "--all-surfaces: $all samples, not more than $count"
ratio=$(( 1000 * all / count ))
[ "$ratio" -ge 1150 ] && [ "$ratio" -le 1250 ] || fail "--all-surfaces / default = $ratio / 1000, expected about 1200"
comment=$(head -c 4096 "$out/a.ply" | tr -c "[:print:]\n" " ")
grep -q "^comment surfaces: facing the region or a camera" <<<"$comment" || fail "no 'surfaces' comment"
leftover=$(find "$out" -name '*.tmp-*' | head -1)
[ -z "$leftover" ] || fail "temporary file left: $leftover"
echo "ok: $count samples facing the region ($all with --all-surfaces), $size bytes"
