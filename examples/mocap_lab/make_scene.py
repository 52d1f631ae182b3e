#!/usr/bin/env python3
"""Writes examples/mocap_lab/scene.json: a 7 x 5 m motion-capture lab with two people who take six
poses (named poses of two moving groups), and two 12-camera rigs that look alike by the volume's
headline numbers but not on the people's bodies (docs/time.md tells the story with numbers).

Usage: python3 examples/mocap_lab/make_scene.py  (rewrites scene.json next to this script)
"""
import json
import math
import os

ROOM_X, ROOM_Y, ROOM_H = 7.0, 5.0, 3.0


def person(name, x, y, material):
    """A standing person (capsules and a sphere) with its feet at (x, y, 0), all in group `name`."""
    parts = [
        ("leg_l", {"capsule": {"radius": 0.075, "length": 0.7, "segments": 12}}, [-0.1, 0.0, 0.45]),
        ("leg_r", {"capsule": {"radius": 0.075, "length": 0.7, "segments": 12}}, [0.1, 0.0, 0.45]),
        ("torso", {"capsule": {"radius": 0.17, "length": 0.42, "segments": 16}}, [0.0, 0.0, 1.2]),
        ("head", {"sphere": {"radius": 0.11, "segments": 16}}, [0.0, 0.0, 1.66]),
        ("arm_l", {"capsule": {"radius": 0.05, "length": 0.5, "segments": 10}}, [-0.27, 0.0, 1.12]),
        ("arm_r", {"capsule": {"radius": 0.05, "length": 0.5, "segments": 10}}, [0.27, 0.0, 1.12]),
    ]
    out = []
    for part, geometry, at in parts:
        o = {"name": f"{name}_{part}", "group": name}
        o.update(geometry)
        o["position"] = [round(x + at[0], 4), round(y + at[1], 4), at[2]]
        o["material"] = material
        o["solid"] = True
        out.append(o)
    return out


def look(cid, position, target, color):
    return {"id": cid, "color": color, "position": [round(v, 4) for v in position],
            "look_at": target, "up": [0, 0, 1], "resolution": [2048, 1536], "hfov_deg": 66,
            "range": {"near": 0.3, "far": 12.0}}


PALETTE = ["#e6194b", "#3cb44b", "#4363d8", "#f58231", "#911eb4", "#46f0f0", "#f032e6", "#bcf60c",
           "#fabebe", "#008080", "#e6beff", "#9a6324"]


def ring_rig():
    """12 cameras spread evenly round the room at 2.6 m, aimed at the volume's centre."""
    cams = []
    for i in range(12):
        a = 2 * math.pi * (i + 0.5) / 12
        x, y = 0.48 * ROOM_X * math.cos(a), 0.47 * ROOM_Y * math.sin(a)
        cams.append(look(f"r{i + 1}", [x, y, 2.6], [0.0, 0.0, 0.9], PALETTE[i]))
    return {"name": "ring", "cameras": cams}


def corners_rig():
    """12 cameras in four corner clusters of three (0.8, 1.7, 2.6 m), aimed at the centre."""
    cams = []
    i = 0
    for sx, sy in [(1, 1), (-1, 1), (-1, -1), (1, -1)]:
        for h in (0.8, 1.7, 2.6):
            x, y = sx * (0.5 * ROOM_X - 0.15), sy * (0.5 * ROOM_Y - 0.15)
            cams.append(look(f"c{i + 1}", [x, y, h], [0.0, 0.0, 1.0], PALETTE[i]))
            i += 1
    return {"name": "corners", "cameras": cams}


def walls():
    t = 0.1
    return [
        {"name": "floor", "box": {"size": [ROOM_X, ROOM_Y, 0.05]}, "position": [0, 0, -0.025],
         "material": "floor", "solid": True},
        {"name": "wall_n", "box": {"size": [ROOM_X, t, ROOM_H]}, "position": [0, 0.5 * ROOM_Y + t / 2, ROOM_H / 2],
         "material": "wall", "solid": True},
        {"name": "wall_s", "box": {"size": [ROOM_X, t, ROOM_H]}, "position": [0, -0.5 * ROOM_Y - t / 2, ROOM_H / 2],
         "material": "wall", "solid": True},
        {"name": "wall_e", "box": {"size": [t, ROOM_Y, ROOM_H]}, "position": [0.5 * ROOM_X + t / 2, 0, ROOM_H / 2],
         "material": "wall", "solid": True},
        {"name": "wall_w", "box": {"size": [t, ROOM_Y, ROOM_H]}, "position": [-0.5 * ROOM_X - t / 2, 0, ROOM_H / 2],
         "material": "wall", "solid": True},
    ]


# Where the two people stand in each pose (feet centre, metres) and which way they face (yaw, deg).
POSES = {
    "apart": ((-1.0, 0.0, 0), (1.0, 0.0, 180)),
    "face_to_face": ((-0.3, 0.0, 0), (0.3, 0.0, 180)),
    "corners": ((-1.5, -1.0, 45), (1.4, 1.0, 225)),
    "one_behind": ((0.0, 0.55, 0), (0.0, -0.55, 180)),
    "side_by_side": ((-0.3, -0.2, 90), (0.2, -0.2, 90)),
    "huddle": ((1.1, -0.7, 30), (1.5, -0.3, 210)),
}
REST = {"a": (-1.0, 0.0), "b": (1.0, 0.0)}


def motions():
    out = {}
    for k, name in enumerate(["a", "b"]):
        poses = {}
        for pose, people in POSES.items():
            x, y, yaw = people[k]
            rx, ry = REST[name]
            poses[pose] = {"move": [round(x - rx, 4), round(y - ry, 4), 0], "yaw_deg": yaw}
        out[name] = {"poses": poses}
    return out


def main():
    scene = {
        "pandora": 1,
        "units": "m",
        "materials": {"floor": {"color": [0.35, 0.35, 0.38]}, "wall": {"color": [0.6, 0.6, 0.62]},
                      "suit_a": {"color": [0.2, 0.25, 0.3]}, "suit_b": {"color": [0.3, 0.2, 0.2]}},
        "objects": walls() + person("a", *REST["a"], "suit_a") + person("b", *REST["b"], "suit_b"),
        "motions": motions(),
        "rigs": [ring_rig(), corners_rig()],
        "study": {
            "region": {"box": {"min": [-2.0, -1.5, 0.05], "max": [2.0, 1.5, 2.05]}},
            "voxel_size": 0.1,
            "fields": ["coverage", "cameras", "sigma_max"],
            "time": {"poses": list(POSES.keys()), "min_cameras": 3},
            "targets": {"objects": ["a", "b"], "points": 3000, "seed": 1},
            "regions": {"centre": {"box": {"min": [-1.0, -1.0, 0.05], "max": [1.0, 1.0, 2.05]}},
                        "feet": {"box": {"min": [-2.0, -1.5, 0.05], "max": [2.0, 1.5, 0.35]}}},
            "calibration": {"target": "board", "samples": 2000, "seed": 1, "min_shared": 20,
                            "board": {"squares": [9, 7], "square_m": 0.06, "tilt_max_deg": 60, "min_px_per_square": 10}},
            "pixel_targets": [{"name": "marker", "size_m": 0.014, "min_px": 4},
                              {"name": "face", "size_m": 0.16, "min_px": 80}],
        },
        "views": {"overview": {"from": [-3.1, -2.2, 2.9], "at": [0.4, 0.2, 0.7], "fov_deg": 70}},
    }
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scene.json")
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
