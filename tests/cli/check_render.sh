#!/usr/bin/env bash
# Renders a scene to PNG and multi-layer EXR and checks them with outside tools: `exrheader`
# (Debian's openexr package) lists the RGB channels and every layer with its type, and the PNG is
# an 8-bit RGB image of the asked size; overlays from `pandora analyze`'s fields.vdb render, and a
# grid the file lacks is a one-line error. No temporary file is left.
# Usage: check_render.sh PANDORA SCENE OUT_DIR
set -eu
pandora=$1; scene=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
"$pandora" render "$scene" --from 3,-2.5,2.5 --at 0,0,0.4 --size 160x90 --out "$out/view.exr" --quiet
"$pandora" render "$scene" --from 3,-2.5,2.5 --at 0,0,0.4 --size 160x90 --out "$out/view.png" --quiet
"$pandora" render "$scene" --camera b --size 64x48 --pattern grid --surface hidden-line --out "$out/camera_b.png" --quiet
command -v exrheader >/dev/null || { echo "FAIL: exrheader not installed (Debian package openexr)"; exit 1; }
header=$(exrheader "$out/view.exr")
for want in "R, 32-bit floating-point" "G, 32-bit floating-point" "B, 32-bit floating-point" \
            "coverage, 32-bit floating-point" "cameras, 32-bit unsigned integer" \
            "resolution, 32-bit floating-point" "sigma_max, 32-bit floating-point" \
            "depth, 32-bit floating-point" "dataWindow (type box2i): (0 0) - (159 89)"; do
  printf '%s\n' "$header" | grep -qF "$want" || { echo "FAIL: exrheader lacks '$want'"; printf '%s\n' "$header"; exit 1; }
done
# PNG signature and IHDR: width 160, height 90, bit depth 8, colour type 2 (RGB).
ihdr=$(od -An -tx1 -j16 -N10 "$out/view.png" | tr -d ' \n')
[ "$ihdr" = "000000a00000005a0802" ] || { echo "FAIL: PNG header $ihdr, expected 160x90 8-bit RGB"; exit 1; }
ihdr=$(od -An -tx1 -j16 -N10 "$out/camera_b.png" | tr -d ' \n')
[ "$ihdr" = "00000040000000300802" ] || { echo "FAIL: camera view PNG header $ihdr, expected 64x48 8-bit RGB"; exit 1; }
# Overlays from a real fields.vdb: a coverage slice and the coverage >= 2 isosurface.
"$pandora" analyze "$scene" --out "$out/fields" --quiet
"$pandora" render "$scene" --from 3,-2.5,2.5 --at 0,0,0.4 --size 160x90 --fields "$out/fields/fields.vdb" \
  --slice resolution --slice-axis x --iso coverage --iso-value 1.5 --out "$out/overlays.png" --quiet
ihdr=$(od -An -tx1 -j16 -N10 "$out/overlays.png" | tr -d ' \n')
[ "$ihdr" = "000000a00000005a0802" ] || { echo "FAIL: overlay PNG header $ihdr"; exit 1; }
# A field the file lacks: one line naming --slice and the grids it has, exit code 2, no image.
set +e
err=$("$pandora" render "$scene" --from 3,-2.5,2.5 --at 0,0,0.4 --fields "$out/fields/fields.vdb" \
  --slice sigma_max --out "$out/missing_grid.png" 2>&1 >/dev/null)
code=$?
set -e
[ "$code" -eq 2 ] || { echo "FAIL: missing grid: exit code $code"; exit 1; }
case "$err" in *"--slice: the fields have no grid 'sigma_max'"*"available: coverage"*) ;;
  *) echo "FAIL: missing grid message: $err"; exit 1;; esac
[ ! -e "$out/missing_grid.png" ] || { echo "FAIL: image written despite the error"; exit 1; }
[ -z "$(ls "$out" | grep -F .tmp)" ] || { echo "FAIL: temporary files left: $(ls "$out")"; exit 1; }
echo "ok: exrheader lists RGB and the layers; PNGs are 8-bit RGB of the asked size"
