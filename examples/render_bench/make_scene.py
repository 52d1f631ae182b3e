#!/usr/bin/env python3
"""Writes examples/render_bench/scene.json: the trauma room (examples/trauma_room/scene.json) with
its curved primitives tessellated finely, about 100k triangles, for `pandora bench --render`.

Deterministic: the same input gives the same file. Capsules and cylinders get 52 segments, spheres
72; boxes stay boxes. The study region grows to the space above and around the table (2 cm voxels)
so that docs/rendering.md can show field slices and isosurfaces across the room. Rerun after
changing the trauma room:
    python3 examples/render_bench/make_scene.py
"""
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.join(HERE, "..", "trauma_room", "scene.json")
SEGMENTS = {"capsule": 52, "cylinder": 52, "sphere": 72}


def main():
    with open(SOURCE) as f:
        scene = json.load(f)
    for obj in scene["objects"]:
        for kind, segments in SEGMENTS.items():
            if kind in obj:
                obj[kind]["segments"] = segments
    scene["study"]["region"] = {"box": {"min": [-0.9, -1.0, 0.75], "max": [1.4, 1.0, 1.95]}}
    scene["study"]["voxel_size"] = 0.02
    scene["study"]["fields"] = ["coverage", "cameras", "resolution", "sigma_max"]
    # Mesh paths (if any) stay relative to the trauma room's folder.
    for obj in scene["objects"]:
        if "mesh" in obj and "file" in obj["mesh"]:
            obj["mesh"]["file"] = os.path.join("..", "trauma_room", obj["mesh"]["file"])
    with open(os.path.join(HERE, "scene.json"), "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
