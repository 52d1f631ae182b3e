"""Imports a surface PLY from `pandora export-surface` with Blender's PLY importer and checks it.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/check_ply_import.py -- FILE.ply
Parses the file independently (header and binary records, with struct), then checks that Blender
made one vertex per record at the same position (float32, so to 1e-6 m) and that every value is
finite and consistent (sigma_max 0 exactly where triangulable is 0, coverage a whole number, colours
grey only where coverage is 0). Exits non-zero and prints FAIL on any difference.
Blender 3.x's importer keeps positions only for a point cloud (colours are per face corner there and
custom properties are ignored); CloudCompare and MeshLab read the extra properties as scalar fields.
"""
import math
import struct
import sys

import addon_utils
import bpy

path = sys.argv[sys.argv.index("--") + 1]
TYPES = {"float": "f", "uchar": "B", "int": "i"}

with open(path, "rb") as f:
    data = f.read()
end = data.index(b"end_header\n") + len(b"end_header\n")
header = data[:end].decode("ascii").splitlines()
assert header[0] == "ply" and header[1] == "format binary_little_endian 1.0", header[:2]
count = None
props = []
for line in header:
    words = line.split()
    if words[:2] == ["element", "vertex"]:
        count = int(words[2])
    elif words and words[0] == "property":
        props.append((words[2], TYPES[words[1]]))
names = [p[0] for p in props]
expected = ["x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "coverage", "resolution",
            "sigma_max", "triangulable", "object"]
if names != expected:
    print(f"FAIL: properties {names}, expected {expected}")
    sys.exit(1)
fmt = "<" + "".join(p[1] for p in props)
size = struct.calcsize(fmt)
if len(data) - end != size * count:
    print(f"FAIL: {len(data) - end} bytes of records for {count} vertices of {size} bytes")
    sys.exit(1)
records = [dict(zip(names, r)) for r in struct.iter_unpack(fmt, data[end:])]
for r in records:
    bad = [k for k, v in r.items() if isinstance(v, float) and not math.isfinite(v)]
    if bad or r["coverage"] != int(r["coverage"]) or (r["triangulable"] == 0) != (r["sigma_max"] == 0):
        print(f"FAIL: inconsistent record {r}")
        sys.exit(1)
    if (r["coverage"] == 0) != ((r["red"], r["green"], r["blue"]) == (128, 128, 128)):
        print(f"FAIL: colour does not follow coverage in {r}")
        sys.exit(1)

addon_utils.enable("io_mesh_ply")
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
result = bpy.ops.import_mesh.ply(filepath=path)
if result != {"FINISHED"} or not bpy.context.selected_objects:
    print(f"FAIL: import returned {result}")
    sys.exit(1)
mesh = bpy.context.selected_objects[0].data
if len(mesh.vertices) != count:
    print(f"FAIL: Blender made {len(mesh.vertices)} vertices, the file has {count}")
    sys.exit(1)
worst = 0.0
for v, r in zip(mesh.vertices, records):
    worst = max(worst, abs(v.co.x - r["x"]), abs(v.co.y - r["y"]), abs(v.co.z - r["z"]))
if worst > 1e-6:
    print(f"FAIL: positions differ by up to {worst} m")
    sys.exit(1)
seen = sum(1 for r in records if r["coverage"] > 0)
tri = sum(r["triangulable"] for r in records)
print(f"ok: Blender imported {count} samples (largest position difference {worst:.2g} m); "
      f"{seen} seen, {tri} triangulable")
