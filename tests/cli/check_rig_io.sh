#!/usr/bin/env bash
# `pandora export-rig` / `pandora import-rig` end to end on a copy of a centimetre scene with
# pinhole, Brown-Conrady and fisheye cameras and odd ids (docs/tool-chain.md):
#  - every format is written; the sheet has one row per camera;
#  - OpenCV YAML and COLMAP exports imported back (as new rigs) differ from the design by 0;
#  - a damaged file: exit 2, one line naming the file and line, the scene file and its folder untouched;
#  - when `colmap` is installed, its own reader (model_converter) loads the exported model and
#    writes back the same cameras and images (numbers to 1e-15 relative); the model it writes
#    imports back to the design.
# Usage: check_rig_io.sh PANDORA SCENE OUT_DIR [colmap]   (colmap: only COLMAP's reader; skipped
# with "skipped: colmap is not installed" where it is not)
set -euo pipefail
pandora=$1; scene=$2; out=$3; mode=${4:-}
if [ "$mode" = colmap ] && ! command -v colmap > /dev/null; then
  echo "skipped: colmap is not installed"; exit 0
fi
rm -rf "$out"; mkdir -p "$out"
cp "$scene" "$out/scene.json"
s="$out/scene.json"
fail() { echo "FAIL: $*"; exit 1; }

check_zero() {  # the import's table: every camera row reads 0.000 mm and 0.0000 deg
  local report=$1 n
  n=$(awk '$0 ~ /^(camera|against|added|updated)/ {next} {print $(NF-3), $(NF-2), ($(NF-1) == $NF)}' "$report" | grep -c '^0.000 0.0000 1$' || true)
  [ "$n" -eq "$cameras" ] || { cat "$report"; fail "$report: $n of $cameras cameras unchanged"; }
}
cameras=$(jq '.rigs[0].cameras | length' "$s")
if [ "$mode" = colmap ]; then
  "$pandora" export-rig "$s" --format colmap --out "$out/colmap" --quiet
fi

if [ "$mode" != colmap ]; then
for f in opencv gltf sheet; do "$pandora" export-rig "$s" --format $f --out "$out/rig.$f" --quiet; done
"$pandora" export-rig "$s" --format colmap --out "$out/colmap" --quiet
for f in "$out/rig.opencv" "$out/rig.gltf" "$out/rig.sheet" "$out/colmap/cameras.txt" "$out/colmap/images.txt" "$out/colmap/points3D.txt"; do
  [ -s "$f" ] || fail "missing $f"
done
head -1 "$out/rig.opencv" | grep -qx '%YAML:1.0' || fail "the YAML does not start with %YAML:1.0"
rows=$(($(wc -l < "$out/rig.sheet") - 1))
[ "$rows" -eq "$cameras" ] || fail "sheet has $rows rows, expected $cameras"
jq -e '.cameras | length == '"$cameras" "$out/rig.gltf" > /dev/null || fail "glTF cameras"

# Round trips as new rigs: every camera moved 0.000 mm, turned 0.0000 deg, same focal length.
"$pandora" import-rig "$s" --from opencv "$out/rig.opencv" --rig design --as from_opencv > "$out/import_opencv.txt"
check_zero "$out/import_opencv.txt"
"$pandora" import-rig "$s" --from colmap "$out/colmap" --rig design --as from_colmap > "$out/import_colmap.txt"
check_zero "$out/import_colmap.txt"
[ -f "$s.bak" ] && [ -f "$s.bak.1" ] || fail "no backups"
cmp -s "$scene" "$s.bak" || fail "the first backup is not the original scene"
[ "$(jq '.rigs | length' "$s")" -eq 3 ] || fail "expected 3 rigs after two imports"

# A damaged file: one line, exit 2, nothing written.
sed 's/^\(\s*image_height:\).*/\1 nan/' "$out/rig.opencv" > "$out/damaged.yml"
cp "$s" "$out/before.json"; ls "$out" > "$out/before.ls"
set +e
"$pandora" import-rig "$s" --from opencv "$out/damaged.yml" --rig design --as x 2> "$out/err.txt"
code=$?
set -e
[ "$code" -eq 2 ] || fail "damaged file: exit $code"
[ "$(grep -c . "$out/err.txt")" -eq 1 ] || fail "damaged file: $(cat "$out/err.txt")"
grep -q 'damaged.yml: line 10: cameras\[0\].image_height: expected a whole number' "$out/err.txt" || fail "message: $(cat "$out/err.txt")"
cmp -s "$s" "$out/before.json" || fail "the scene file changed"
ls "$out" | grep -v '^err.txt$' | diff - "$out/before.ls" > /dev/null || fail "files appeared: $(ls "$out")"

echo "ok: export-rig and import-rig round trips ($cameras cameras)"
exit 0
fi

# COLMAP's own reader.
if command -v colmap > /dev/null; then
  mkdir -p "$out/colmap_txt"
  colmap model_converter --input_path "$out/colmap" --output_path "$out/colmap_txt" --output_type TXT > "$out/colmap.log" 2>&1 ||
    { cat "$out/colmap.log"; fail "colmap model_converter refused the model"; }
  python3 - "$out/colmap" "$out/colmap_txt" <<'PY' || fail "COLMAP's model differs"
import sys
def lines(path):
    out = {}
    rows = [l for l in open(path) if not l.startswith("#")]
    for l in rows:
        t = l.split()
        if t and t[0].isdigit() and len(t) > 4:
            out[int(t[0])] = t
    return out
def same(a, b):
    try:
        x, y = float(a), float(b)
        return x == y or abs(x - y) <= 1e-15 * max(abs(x), abs(y))
    except ValueError:
        return a == b
bad = 0
for name in ("cameras.txt", "images.txt"):
    mine, theirs = lines(f"{sys.argv[1]}/{name}"), lines(f"{sys.argv[2]}/{name}")
    if mine.keys() != theirs.keys():
        print(name, "ids differ", sorted(mine), sorted(theirs)); bad += 1
    for k in mine:
        a, b = mine[k], theirs.get(k, [])
        if len(a) != len(b) or not all(same(x, y) for x, y in zip(a, b)):
            print(name, "differs:", " ".join(a), "|", " ".join(b)); bad += 1
print(f"colmap model_converter: {len(lines(sys.argv[2] + '/cameras.txt'))} cameras, "
      f"{len(lines(sys.argv[2] + '/images.txt'))} images, {bad} differences")
sys.exit(1 if bad else 0)
PY
  "$pandora" import-rig "$s" --from colmap "$out/colmap_txt" --rig design --as via_colmap > "$out/import_colmap_txt.txt"
  check_zero "$out/import_colmap_txt.txt"
else
  echo "skipped: colmap is not installed"; exit 0
fi
echo "ok: COLMAP's model_converter read the exported model back ($cameras cameras)"
