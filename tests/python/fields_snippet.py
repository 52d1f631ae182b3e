import json
import sys

import pyopenvdb as vdb

path = sys.argv[1] if len(sys.argv) > 1 else "out/fields.vdb"
grids, meta = vdb.readAll(path)  # every grid: FloatGrid or BoolGrid
by_name = {g.name: g for g in grids}
rig = json.loads(meta["rig"])
print("rig", meta["rig_name"], "with", len(rig["cameras"]), "cameras; scene", meta["scene_sha256"][:12])

coverage = by_name["coverage"]  # whole numbers: how many cameras see each voxel
print("free region voxels:", coverage.activeVoxelCount())
for g in grids:
    if g.name.startswith("visible/"):  # one BoolGrid per camera: active where it sees
        print("camera", g["camera_index"], repr(g["camera_id"]), "sees", g.activeVoxelCount(), "voxels")

xyz = (0.025, 0.025, 0.525)  # a point in metres, world frame
ijk = tuple(round(c) for c in coverage.transform.worldToIndex(xyz))
print("voxel", ijk, "is seen by", int(coverage.getConstAccessor().getValue(ijk)), "cameras")
