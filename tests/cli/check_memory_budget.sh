#!/usr/bin/env bash
# The memory budget bounds the process's peak (docs/robustness.md): 1,000 cameras over 4,096 voxels
# with the per-camera 'cameras' field (one OpenVDB grid per camera, ~300 kB each) once peaked at
# 2.6 times the budget. Under a budget below the estimate: refused, one line, nothing written; under
# the estimate plus 8 MiB: it runs, and summary.json's peak resident memory less the process's
# baseline (the same scene with one camera, coverage alone: libraries, scene, BVH) is within it.
# usage: check_memory_budget.sh PANDORA PYTHON OUT_DIR
set -uo pipefail
pandora=$1 python=$2 out=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$out"
mkdir -p "$out"
"$python" - "$out/many.json" <<'PY'
import json, math, sys
cams = []
for i in range(1000):
    a = 2 * math.pi * i / 1000
    cams.append({"id": f"c{i}", "position": [3 * math.cos(a), 3 * math.sin(a), 1.0 + 0.5 * math.sin(7 * a)],
                 "look_at": [0, 0, 0.5], "resolution": [640, 480], "hfov_deg": 40})
json.dump({"pandora": 1, "objects": [{"name": "floor", "box": {"size": [8, 8, 0.1]}, "position": [0, 0, -0.05]}],
           "rigs": [{"name": "many", "cameras": cams}],
           "study": {"region": {"box": {"min": [-0.4, -0.4, 0.1], "max": [0.4, 0.4, 0.9]}}, "voxel_size": 0.05}},
          open(sys.argv[1], "w"))
PY
"$pandora" analyze "$out/many.json" --memory-budget 64 --out "$out/small" 2> "$out/err"
rc=$?
[ $rc -eq 2 ] || fail "64 MiB budget: exit $rc"
[ "$(wc -l < "$out/err")" -eq 1 ] && grep -q "with the rig's 1000 cameras), over the budget of 64 MiB" "$out/err" || fail "message: $(cat "$out/err")"
[ ! -e "$out/small" ] || fail "a refused run left $out/small"
need=$(sed -n 's/.*needs about \([0-9]*\) MiB.*/\1/p' "$out/err")
budget=$((need + 8))
"$pandora" analyze "$out/many.json" --memory-budget $budget --out "$out/fits" --quiet || fail "budget $budget MiB: exit $?"
peak=$(jq '.timing.peak_rss_mib' "$out/fits/summary.json")
# The budget bounds the process's data; the program itself (code and libraries) comes on top: its
# baseline is the same command's peak on the same small scene with one camera and coverage alone.
jq '.rigs[0].cameras |= .[0:1]' "$out/many.json" > "$out/one.json"
"$pandora" analyze "$out/one.json" --fields coverage --out "$out/one" --quiet || fail "one camera: exit $?"
base=$(jq '.timing.peak_rss_mib' "$out/one/summary.json")
"$python" -c "import sys; p, b, o = float('$peak'), $budget, float('$base'); sys.exit(0 if p - o <= b else 1)" ||
  fail "peak $peak MiB less the baseline $base MiB is over the budget of $budget MiB"
echo "many cameras: estimate $need MiB, peak $peak MiB ($base MiB without the work) within a budget of $budget MiB"

# A thin region touching a solid: a 2 cm slab (one voxel) over a floor, 10 m x 10 m. Memory goes by
# 8^3 blocks (an OpenVDB leaf holds 512 values however few are active): counted by voxels, the
# estimate was 8 times too low and the run peaked at twice its budget.
"$python" - "$out/thin.json" <<'PY'
import json, math, sys
cams = [{"id": f"c{i}", "position": [9 * math.cos(i * math.pi / 4), 9 * math.sin(i * math.pi / 4), 3],
         "look_at": [0, 0, 0], "resolution": [1280, 960], "hfov_deg": 70} for i in range(8)]
json.dump({"pandora": 1, "objects": [{"name": "floor", "box": {"size": [30, 30, 0.2]}, "position": [0, 0, -0.1]}],
           "rigs": [{"name": "ring", "cameras": cams}],
           "study": {"region": {"box": {"min": [-5, -5, 0], "max": [5, 5, 0.02]}}, "voxel_size": 0.02,
                     "fields": ["coverage", "resolution", "sigma_max"]}},
          open(sys.argv[1], "w"))
PY
"$pandora" analyze "$out/thin.json" --memory-budget 16 --out "$out/thin_small" 2> "$out/thin_err"
rc=$?
[ $rc -eq 2 ] && [ "$(wc -l < "$out/thin_err")" -eq 1 ] || fail "thin region, 16 MiB: exit $rc, $(cat "$out/thin_err")"
need=$(sed -n 's/.*needs about \([0-9]*\) MiB.*/\1/p' "$out/thin_err")
budget=$((need + 8))
"$pandora" analyze "$out/thin.json" --memory-budget $budget --out "$out/thin_fits" --quiet || fail "thin, budget $budget MiB: exit $?"
peak=$(jq '.timing.peak_rss_mib' "$out/thin_fits/summary.json")
"$python" -c "import sys; p, b, o = float('$peak'), $budget, float('$base'); sys.exit(0 if p - o <= b else 1)" ||
  fail "thin region: peak $peak MiB less the baseline $base MiB is over the budget of $budget MiB"
echo "thin region: estimate $need MiB, peak $peak MiB within a budget of $budget MiB"
# A mesh import: the importer's transient peak comes before any triangle count is known, so the
# budget bounds each import itself. A 99,372-triangle OBJ (a subdivided cube) needs tens of MiB.
"$python" - "$out/cube.obj" <<'PY'
import sys
n = 91
index, verts, faces = {}, [], []
def v(p):
    if p not in index:
        index[p] = len(verts) + 1
        verts.append(p)
    return index[p]
for axis in range(3):
    for side in (-1, 1):
        u, w = (axis + 1) % 3, (axis + 2) % 3
        def P(a, b):
            p = [0, 0, 0]; p[axis] = side * n; p[u] = -n + 2 * a; p[w] = -n + 2 * b
            return tuple(p)
        for i in range(n):
            for j in range(n):
                a, b, c, d = v(P(i, j)), v(P(i + 1, j)), v(P(i + 1, j + 1)), v(P(i, j + 1))
                faces += [(a, b, c), (a, c, d)] if side > 0 else [(a, c, b), (a, d, c)]
with open(sys.argv[1], "w") as f:
    f.writelines("v %.6f %.6f %.6f\n" % (x / n, y / n, z / n) for x, y, z in verts)
    f.writelines("f %d %d %d\n" % t for t in faces)
PY
jq '.objects += [{"name": "cube", "mesh": {"file": "cube.obj", "up_axis": "z"}, "position": [3, 3, 1]}] | .rigs[0].cameras |= .[0:2]' \
  "$out/thin.json" > "$out/mesh.json"
"$pandora" analyze "$out/mesh.json" --memory-budget 8 --out "$out/mesh_small" 2> "$out/mesh_err"
rc=$?
[ $rc -eq 2 ] && [ "$(wc -l < "$out/mesh_err")" -eq 1 ] &&
  grep -qF "mesh.file: reading the mesh file needs more than the memory budget of 8 MiB (--memory-budget) (" "$out/mesh_err" ||
  fail "mesh import over --memory-budget 8: exit $rc, $(cat "$out/mesh_err")"
jq '.study.memory_budget_mb = 8' "$out/mesh.json" > "$out/mesh_in_file.json"
"$pandora" analyze "$out/mesh_in_file.json" --out "$out/mesh_small" 2> "$out/mesh_err"
rc=$?
[ $rc -eq 2 ] && grep -q 'memory budget of 8 MiB (\$.study.memory_budget_mb of ' "$out/mesh_err" ||
  fail "mesh import over the study's budget: exit $rc, $(cat "$out/mesh_err")"
[ ! -e "$out/mesh_small" ] || fail "a refused run left $out/mesh_small"
budget=200
"$pandora" analyze "$out/mesh.json" --memory-budget $budget --out "$out/mesh_fits" --quiet || fail "mesh, budget $budget MiB: exit $?"
peak=$(jq '.timing.peak_rss_mib' "$out/mesh_fits/summary.json")
"$python" -c "import sys; p, b, o = float('$peak'), $budget, float('$base'); sys.exit(0 if p - o <= b else 1)" ||
  fail "mesh: peak $peak MiB less the baseline $base MiB is over the budget of $budget MiB"
echo "mesh import: refused under 8 MiB (option and study), peak $peak MiB within a budget of $budget MiB"
echo "ok: the memory budget bounds the peak (many cameras, a thin region, a mesh import)"
