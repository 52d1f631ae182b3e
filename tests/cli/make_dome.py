#!/usr/bin/env python3
"""Writes a scene with one rig of N cameras on a spiral dome around a small stage (for the
large-rig tests: fields, suggest and render with 1000 cameras). Usage: make_dome.py N OUT.json"""
import json
import math
import sys

n = int(sys.argv[1])
cams = []
for i in range(n):
    z = 0.5 + 3.0 * (i + 0.5) / n
    a = i * 2.399963229728653  # golden angle
    r = math.sqrt(max(1.0, 25.0 - (z - 0.5) ** 2))
    cams.append({"id": f"c{i:04d}", "position": [round(r * math.cos(a), 4), round(r * math.sin(a), 4), round(z, 4)],
                 "look_at": [0.0, 0.0, 0.9], "up": [0, 0, 1], "resolution": [640, 480],
                 "hfov_deg": 30 + (i % 5) * 8})
scene = {
    "pandora": 1, "units": "m",
    "objects": [
        {"name": "floor", "box": {"size": [12, 12, 0.05]}, "position": [0, 0, -0.025], "solid": True},
        {"name": "actor", "capsule": {"radius": 0.2, "length": 1.3, "segments": 16},
         "position": [0.2, 0.1, 0.85], "solid": True},
    ],
    "rigs": [{"name": "dome", "cameras": cams}],
    "study": {"region": {"box": {"min": [-1.5, -1.5, 0.05], "max": [1.5, 1.5, 2.0]}}, "voxel_size": 0.1,
              "fields": ["coverage", "cameras", "resolution", "sigma_max"],
              "pixel_sigma": 0.5},
    "views": {"overview": {"from": [-7, -6, 5], "at": [0, 0, 0.9], "fov_deg": 60}},
}
with open(sys.argv[2], "w") as f:
    json.dump(scene, f)
