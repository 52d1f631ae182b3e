# Converts a glTF file to FBX through Blender (its glTF importer and FBX exporter, every action
# baked), as a user would bring a rigged, animated person from Blender to Pandora.
# Usage: blender -b --factory-startup --python-exit-code 1 --python gltf_to_fbx.py -- IN.gltf OUT.fbx
import sys

import numpy

if not hasattr(numpy, "bool"):  # Blender 3.4's glTF importer uses numpy.bool, gone in numpy 1.24
    numpy.bool = bool

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=argv[0])
bpy.ops.export_scene.fbx(filepath=argv[1], bake_anim=True, add_leaf_bones=False,
                         bake_anim_use_all_actions=True, bake_anim_use_nla_strips=False)
print("ok: Blender wrote", argv[1])
