"""Imports a fields.vdb with Blender's own volume importer and checks the grids it finds.

Run: blender -b --factory-startup --python tests/blender/check_volume_import.py -- \
         FIELDS.vdb MIN_X MIN_Y MIN_Z MAX_X MAX_Y MAX_Z VOXEL_SIZE NAME=TYPE...
NAME=TYPE are the grids expected and Blender's data type for each (FLOAT for the field grids and
coverage, BOOLEAN for the per-camera grids "visible/<id>"). Exits non-zero (and prints FAIL) when
the file does not load, a grid is missing, has another type or does not load, Blender finds a grid
not expected, or the volume's bounds do not match the region (Blender gives the voxel centres of the
grids' leaf nodes: the low corner is region.min + voxel_size / 2, the high one within one 8-voxel
leaf of region.max).
"""
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
path = args[0]
region_min = [float(v) for v in args[1:4]]
region_max = [float(v) for v in args[4:7]]
voxel = float(args[7])
expected = dict(a.split("=", 1) for a in args[8:])

bpy.ops.object.volume_import(filepath=path)
obj = bpy.context.selected_objects[0]
volume = obj.data
volume.grids.load()
found = {}
loaded = True
for grid in volume.grids:
    grid.load()
    found[grid.name] = grid.data_type
    loaded = loaded and grid.is_loaded
    print(f"grid {grid.name!r}: {grid.data_type}, loaded {grid.is_loaded}")
corners = [tuple(v) for v in obj.bound_box]
lo = [min(c[i] for c in corners) for i in range(3)]
hi = [max(c[i] for c in corners) for i in range(3)]
print(f"bounds {lo} .. {hi}")
if not volume.grids.is_loaded or not loaded:
    print("FAIL: Blender did not load every grid")
    sys.exit(1)
if found != expected:
    print(f"FAIL: expected grids {expected}, Blender found {found}")
    sys.exit(1)
for a in range(3):
    if abs(lo[a] - (region_min[a] + voxel / 2)) > 1e-5 or not (
            region_max[a] - voxel / 2 - 1e-5 <= hi[a] <= region_max[a] + 8 * voxel + 1e-5):
        print(f"FAIL: bounds {lo} .. {hi} do not match the region {region_min} .. {region_max}")
        sys.exit(1)
print(f"ok: Blender imported every grid ({len(found)}: "
      f"{sum(t == 'BOOLEAN' for t in found.values())} BOOLEAN, {sum(t == 'FLOAT' for t in found.values())} FLOAT)")
sys.exit(0)
