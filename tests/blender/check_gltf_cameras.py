"""Imports a glTF from `pandora export-rig --format gltf` with Blender's own importer and checks
every camera against the rig's OpenCV YAML export (world -> camera R, T in metres, Z up):
position to 1e-6 m, optical axis and image up to 1e-6 (Blender cameras look down their local -Z
with +Y up; Blender converts glTF's Y up back to Z up). Also one mesh object per scene object.
Usage: blender -b --factory-startup --python check_gltf_cameras.py -- SCENE.gltf RIG.yml OBJECTS
"""
import re
import sys

import bpy
import numpy
from mathutils import Vector

if not hasattr(numpy, "bool"):  # Blender 3.4's glTF importer uses numpy.bool, gone in numpy 1.24
    numpy.bool = bool

args = sys.argv[sys.argv.index("--") + 1:]
gltf, yml, objects = args[0], args[1], int(args[2])


def read_rig(path):
    """The cameras of Pandora's OpenCV YAML: id -> (R rows, T)."""
    text = open(path, encoding="utf-8").read()
    cams = {}
    for block in text.split("\n   -\n")[1:]:
        cid = re.search(r'^\s+id: "((?:[^"\\]|\\.)*)"$', block, re.M).group(1)
        cid = cid.replace('\\"', '"').replace("\\\\", "\\")

        def matrix(key):
            m = re.search(key + r": !!opencv-matrix\n(?:.*\n){3}\s+data: \[([^\]]*)\]", block)
            return [float(v) for v in m.group(1).replace("\n", " ").split(",")]
        r, t = matrix("R"), matrix("T")
        cams[cid] = ([r[0:3], r[3:6], r[6:9]], t)
    return cams


bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=gltf)
rig = read_rig(yml)
found = {o.name: o for o in bpy.data.objects if o.type == "CAMERA"}
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
errors = []
if len(meshes) != objects:
    errors.append(f"{len(meshes)} mesh objects, expected {objects}")
if len(found) != len(rig):
    errors.append(f"{len(found)} cameras, expected {len(rig)}: {sorted(found)}")
worst_p = worst_d = 0.0
for cid, (r, t) in rig.items():
    obj = found.get(cid)
    if obj is None:
        errors.append(f"camera {cid!r} missing; Blender has {sorted(found)}")
        continue
    # Centre -R^T T; optical axis = R's third row; image up = -(R's second row).
    centre = Vector([-sum(r[i][j] * t[i] for i in range(3)) for j in range(3)])
    axis = Vector(r[2])
    up = -Vector(r[1])
    m = obj.matrix_world
    pos = m.translation
    b_axis = -(m.to_3x3() @ Vector((0, 0, 1)))
    b_up = m.to_3x3() @ Vector((0, 1, 0))
    dp = (pos - centre).length
    dd = max((b_axis.normalized() - axis).length, (b_up.normalized() - up).length)
    worst_p, worst_d = max(worst_p, dp), max(worst_d, dd)
    if dp > 1e-6:
        errors.append(f"camera {cid!r} at {tuple(pos)}, expected {tuple(centre)} ({dp:.3g} m)")
    if dd > 1e-6:
        errors.append(f"camera {cid!r} orientation off by {dd:.3g}")
print(f"blender: {len(found)} cameras, {len(meshes)} meshes; worst position error {worst_p:.3g} m, "
      f"worst axis error {worst_d:.3g}")
if errors:
    print("\n".join("FAIL: " + e for e in errors))
    sys.exit(1)
print(f"ok: Blender imported every camera ({len(found)})")
