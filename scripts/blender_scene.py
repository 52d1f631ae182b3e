"""Pandora's scene and fields in Blender: the room and the cameras from a glTF that
`pandora export-rig --format gltf` wrote, the fields from a fields.vdb that `pandora analyze` wrote,
as a volume with a ready material (docs/tool-chain.md, "Blender").

Run (Blender 3.x, no window needed):
    blender -b --factory-startup --python scripts/blender_scene.py -- \
        [--gltf scene.gltf] --vdb out/fields.vdb [--field coverage] [--max VALUE] \
        [--save scene.blend] [--render picture.png --size 640x400 --samples 8]

The volume's density follows the chosen field (`coverage` by default; any float grid of the file:
resolution, sigma_max, ptz_reach_time, ...), scaled so that `--max` (default: the grid's largest
value) is opaque enough to read through the room, and its colour runs through viridis from 0 to
--max. The first camera of the glTF becomes the scene camera. Prints one line per thing it made
and exits non-zero with a FAIL line when an input does not load.
"""
import argparse
import sys

import bpy
import numpy

if not hasattr(numpy, "bool"):  # Blender 3.4's glTF importer uses numpy.bool, gone in numpy 1.24
    numpy.bool = bool

VIRIDIS = [(0.0, (0.267, 0.005, 0.329)), (0.25, (0.229, 0.322, 0.546)), (0.5, (0.128, 0.567, 0.551)),
           (0.75, (0.369, 0.789, 0.383)), (1.0, (0.993, 0.906, 0.144))]


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def parse():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender_scene.py")
    p.add_argument("--gltf")
    p.add_argument("--vdb", required=True)
    p.add_argument("--field", default="coverage")
    p.add_argument("--max", type=float)
    p.add_argument("--save")
    p.add_argument("--render")
    p.add_argument("--size", default="640x400")
    p.add_argument("--samples", type=int, default=8)
    return p.parse_args(argv)


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)


def import_gltf(path):
    before = set(bpy.data.objects)
    try:
        bpy.ops.import_scene.gltf(filepath=path)
    except RuntimeError as e:
        fail(f"{path}: the glTF did not load: {e}")
    new = [o for o in bpy.data.objects if o not in before]
    cameras = [o for o in new if o.type == "CAMERA"]
    meshes = [o for o in new if o.type == "MESH"]
    print(f"glTF {path}: {len(meshes)} meshes, {len(cameras)} cameras")
    return cameras


def import_volume(path, field):
    before = set(bpy.data.objects)
    bpy.ops.object.volume_import(filepath=path)
    new = [o for o in bpy.data.objects if o not in before and o.type == "VOLUME"]
    if not new:
        fail(f"{path}: no volume was imported")
    obj = new[0]
    obj.name = "pandora_fields"
    volume = obj.data
    volume.grids.load()
    names = [g.name for g in volume.grids]
    if not volume.grids.is_loaded:
        fail(f"{path}: Blender could not read the grids")
    if field not in names:
        fail(f"{path}: no grid '{field}' (it has: {', '.join(names)})")
    grid = volume.grids[field]
    if grid.data_type != "FLOAT":
        fail(f"{path}: grid '{field}' is {grid.data_type}, not a float field")
    print(f"volume {path}: {len(names)} grids, showing '{field}'")
    return obj


def volume_material(obj, field, vmax):
    mat = bpy.data.materials.new("pandora_" + field)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    shader = nodes.new("ShaderNodeVolumePrincipled")
    attr = nodes.new("ShaderNodeAttribute")
    attr.attribute_name = field
    # Normalised value v / vmax, clamped: the colour ramp's input and the density.
    norm = nodes.new("ShaderNodeMath")
    norm.operation = "DIVIDE"
    norm.use_clamp = True
    norm.inputs[1].default_value = vmax
    ramp = nodes.new("ShaderNodeValToRGB")
    elements = ramp.color_ramp.elements
    elements[0].position, elements[0].color = VIRIDIS[0][0], (*VIRIDIS[0][1], 1.0)
    elements[1].position, elements[1].color = VIRIDIS[-1][0], (*VIRIDIS[-1][1], 1.0)
    for pos, rgb in VIRIDIS[1:-1]:
        e = elements.new(pos)
        e.color = (*rgb, 1.0)
    density = nodes.new("ShaderNodeMath")
    density.operation = "MULTIPLY"
    density.inputs[1].default_value = 2.0  # a density of 2 per metre at --max: the room stays readable
    links.new(attr.outputs["Fac"], norm.inputs[0])
    links.new(norm.outputs["Value"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], shader.inputs["Color"])
    # The field glows in its colour, so it reads without lights in the room.
    links.new(ramp.outputs["Color"], shader.inputs["Emission Color"])
    shader.inputs["Emission Strength"].default_value = 1.0
    links.new(norm.outputs["Value"], density.inputs[0])
    links.new(density.outputs["Value"], shader.inputs["Density"])
    links.new(shader.outputs["Volume"], out.inputs["Volume"])
    obj.data.materials.clear()
    obj.data.materials.append(mat)
    print(f"material {mat.name}: viridis 0 .. {vmax:g}, density 2 per metre at the top")
    return mat


def grid_max(path, field):
    """The largest value of the grid (Blender does not expose it: read the VDB's metadata)."""
    try:
        import pyopenvdb  # Debian's python3-openvdb, when installed
        return float(pyopenvdb.read(path, field).evalMinMax()[1])
    except Exception:
        return None


def main():
    args = parse()
    clear_scene()
    cameras = import_gltf(args.gltf) if args.gltf else []
    obj = import_volume(args.vdb, args.field)
    vmax = args.max or grid_max(args.vdb, args.field) or 1.0
    volume_material(obj, args.field, vmax)
    scene = bpy.context.scene
    if cameras:
        scene.camera = cameras[0]
        print(f"scene camera: {cameras[0].name}")
    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=args.save)
        print(f"saved {args.save}")
    if args.render:
        if not scene.camera:
            fail("--render needs a camera: give --gltf")
        w, h = (int(v) for v in args.size.split("x"))
        scene.render.engine = "CYCLES"
        scene.cycles.samples = args.samples
        scene.cycles.device = "CPU"
        scene.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise
        scene.render.resolution_x, scene.render.resolution_y = w, h
        scene.render.filepath = args.render
        bpy.ops.render.render(write_still=True)
        print(f"rendered {args.render}")


main()
