#!/usr/bin/env bash
# `pandora render` with a generated rig of 1000 cameras (issue 10: no 64-camera limit): the EXR is
# written with the coverage layer and, beyond 64 cameras, no `cameras` bitmask channel, and its
# `pandora_layers` attribute says why. (One render: loading 1000 cameras takes about a second.)
# Usage: check_render_many_cameras.sh PANDORA OUT_DIR
set -eu
pandora=$1; out=$2
rm -rf "$out"; mkdir -p "$out"
python3 - "$out/scene.json" <<'PY'
import json, math, sys
cams = []
for i in range(1000):
    a = 2 * math.pi * i / 1000
    r = 3.0 + (i % 5) * 0.4
    cams.append({"id": "c%d" % i, "position": [r * math.cos(a), r * math.sin(a), 1.0 + (i % 7) * 0.4],
                 "look_at": [0.5 * math.cos(3 * a), 0.5 * math.sin(3 * a), 0.3],
                 "resolution": [64, 48], "hfov_deg": 30 + (i % 4) * 10})
scene = {"pandora": 1,
         "objects": [{"name": "floor", "plane": {"size": [12, 12]}},
                     {"name": "block", "box": {"size": [0.6, 0.6, 0.8]}, "position": [0, 0, 0.4]}],
         "rigs": [{"name": "stage", "cameras": cams}],
         "study": {"region": {"box": {"min": [-1, -1, 0], "max": [1, 1, 1]}}, "voxel_size": 0.1}}
json.dump(scene, open(sys.argv[1], "w"))
PY
"$pandora" render "$out/scene.json" --from 4,-3,3.5 --at 0,0,0.3 --size 96x72 --out "$out/many.exr" > "$out/log.txt"
grep -q "1000 enabled cameras" "$out/log.txt" || { echo "FAIL: $(cat "$out/log.txt")"; exit 1; }
command -v exrheader >/dev/null || { echo "FAIL: exrheader not installed (Debian package openexr)"; exit 1; }
header=$(exrheader "$out/many.exr")
printf '%s\n' "$header" | grep -qF "coverage, 32-bit floating-point" || { echo "FAIL: no coverage layer"; printf '%s\n' "$header"; exit 1; }
if printf '%s\n' "$header" | grep -qE "^ +cameras(_hi)?, "; then
  echo "FAIL: a cameras bitmask channel for a rig of 1000 cameras"; printf '%s\n' "$header"; exit 1
fi
printf '%s\n' "$header" | grep -qF "cameras: not written, the rig has 1000 cameras" || { echo "FAIL: pandora_layers does not say why"; printf '%s\n' "$header"; exit 1; }
echo "ok: 1000 cameras render to EXR (coverage, no bitmask channel)"
