#!/usr/bin/env python3
"""Writes scene.json: a motion-capture stage with 24 cameras, the example of `pandora bench
--incremental` and of large rigs.

An 8 m x 8 m studio with a 4 m x 4 m x 2.2 m capture volume in the middle; two performers and two
props stand in it. 16 cameras hang on a square truss at 3.2 m (four per side, aimed at points
spread through the volume) and 8 stand on low tripods at 0.9 m around it, aimed up and across so
that feet and the underside of arms are seen. Every camera is a 2048 x 1088 machine-vision camera
with a 56 degree lens and mild barrel distortion, working range 0.5 to 9 m. Built from primitives,
so the example needs no binary assets.

Run it after changing the parameters below; the JSON file it writes is committed.
Units: metres, world Z up.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))

VOLUME_MIN = [-2.0, -2.0, 0.05]
VOLUME_MAX = [2.0, 2.0, 2.25]
TRUSS_HALF = 3.4   # the truss square's half side, metres
TRUSS_Z = 3.2
TRIPOD_RADIUS = 3.6
TRIPOD_Z = 0.9
PALETTE = ["#e6194b", "#3cb44b", "#4363d8", "#f58231", "#911eb4", "#42d4f4", "#f032e6", "#bfef45",
           "#fabed4", "#469990", "#dcbeff", "#9a6324", "#fffac8", "#800000", "#aaffc3", "#808000",
           "#ffd8b1", "#000075", "#a9a9a9", "#ffe119", "#e6beff", "#1e90ff", "#ff7f50", "#2e8b57"]


def r3(v):
    return [round(x, 4) for x in v]


def norm(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def quat_z_to(d):
    """Quaternion [w, x, y, z] rotating +Z onto direction d."""
    d = norm(d)
    c = d[2]
    if c > 1 - 1e-12:
        return [1.0, 0.0, 0.0, 0.0]
    if c < -1 + 1e-12:
        return [0.0, 1.0, 0.0, 0.0]
    axis = [-d[1], d[0], 0.0]  # z x d
    q = [1.0 + c] + axis
    n = math.sqrt(sum(x * x for x in q))
    return [round(x / n, 9) for x in q]


def capsule(name, a, b, radius, material):
    d = [y - x for x, y in zip(a, b)]
    length = math.sqrt(sum(x * x for x in d))
    return {"name": name, "capsule": {"radius": radius, "length": round(max(0.01, length - 2 * radius), 4),
                                      "segments": 16},
            "position": r3([(x + y) / 2 for x, y in zip(a, b)]), "quaternion": quat_z_to(d),
            "material": material, "solid": True}


def performer(name, x, y, facing_deg, height, arms_up):
    """A standing performer, arms out (a T-pose) or raised."""
    f = math.radians(facing_deg)
    left = [-math.sin(f), math.cos(f), 0.0]
    s = height / 1.75
    hip = [x, y, 0.92 * s]
    shoulder = [x, y, 1.44 * s]
    objs = []
    for side, sgn in (("l", 1), ("r", -1)):
        foot = [x + sgn * 0.12 * s * left[0], y + sgn * 0.12 * s * left[1], 0.06]
        objs.append(capsule(f"{name}/leg_{side}", foot, [hip[0] + sgn * 0.1 * s * left[0],
                                                          hip[1] + sgn * 0.1 * s * left[1], hip[2]],
                            0.07 * s, "suit"))
        sh = [shoulder[0] + sgn * 0.19 * s * left[0], shoulder[1] + sgn * 0.19 * s * left[1], shoulder[2]]
        if arms_up:
            hand = [sh[0] + sgn * 0.15 * s * left[0], sh[1] + sgn * 0.15 * s * left[1], sh[2] + 0.62 * s]
        else:
            hand = [sh[0] + sgn * 0.68 * s * left[0], sh[1] + sgn * 0.68 * s * left[1], sh[2] - 0.02]
        objs.append(capsule(f"{name}/arm_{side}", sh, hand, 0.045 * s, "suit"))
    objs.append(capsule(f"{name}/torso", hip, shoulder, 0.16 * s, "suit"))
    objs.append({"name": f"{name}/head", "sphere": {"radius": round(0.105 * s, 4), "segments": 20},
                 "position": r3([x, y, 1.63 * s]), "material": "suit", "solid": True})
    return objs


def objects():
    objs = [{"name": "floor", "box": {"size": [8.0, 8.0, 0.05]}, "position": [0, 0, -0.025],
             "material": "floor", "solid": True}]
    objs += performer("performer_a", -0.6, 0.3, 20, 1.80, False)
    objs += performer("performer_b", 0.9, -0.5, 200, 1.65, True)
    objs.append({"name": "crate", "box": {"size": [0.6, 0.6, 0.6]}, "position": [1.2, 1.2, 0.3],
                 "material": "prop", "solid": True})
    objs.append({"name": "stool", "cylinder": {"radius": 0.2, "height": 0.5, "segments": 24},
                 "position": [-1.3, -1.2, 0.25], "material": "prop", "solid": True})
    # The truss (outside the volume, so it only holds the cameras).
    for i, (size, pos) in enumerate((([6.8, 0.1, 0.1], [0, TRUSS_HALF, TRUSS_Z + 0.12]),
                                     ([6.8, 0.1, 0.1], [0, -TRUSS_HALF, TRUSS_Z + 0.12]),
                                     ([0.1, 6.8, 0.1], [TRUSS_HALF, 0, TRUSS_Z + 0.12]),
                                     ([0.1, 6.8, 0.1], [-TRUSS_HALF, 0, TRUSS_Z + 0.12]))):
        objs.append({"name": f"truss_{i + 1}", "box": {"size": size}, "position": pos,
                     "material": "truss", "solid": True})
    return objs


def camera(i, pos, target):
    return {"id": f"c{i + 1:02d}", "color": PALETTE[i], "position": r3(pos), "look_at": r3(target),
            "up": [0, 0, 1], "resolution": [2048, 1088], "hfov_deg": 56,
            "distortion": {"model": "brown_conrady", "k1": -0.05, "k2": 0.005},
            "range": {"near": 0.5, "far": 9.0}}


def stage24():
    cams = []
    # Truss: four per side at -2.4, -0.8, 0.8, 2.4 along the side; aimed at points spread across the
    # volume at waist height, alternately near and far.
    along = (-2.4, -0.8, 0.8, 2.4)
    sides = (((1, 0), (0, 1)), ((0, 1), (-1, 0)), ((-1, 0), (0, -1)), ((0, -1), (1, 0)))
    for side, (outward, tangent) in enumerate(sides):
        for k, t in enumerate(along):
            pos = [outward[0] * TRUSS_HALF + tangent[0] * t, outward[1] * TRUSS_HALF + tangent[1] * t,
                   TRUSS_Z]
            reach = 0.6 if k % 2 == 0 else -0.4  # aim past or short of the centre
            target = [-outward[0] * reach - tangent[0] * 0.3 * t, -outward[1] * reach - tangent[1] * 0.3 * t,
                      0.9 + 0.15 * (k % 2)]
            cams.append(camera(len(cams), pos, target))
    # Tripods: eight around the volume, low, aimed up and across.
    for k in range(8):
        a = math.radians(22.5 + 45 * k)
        pos = [TRIPOD_RADIUS * math.cos(a), TRIPOD_RADIUS * math.sin(a), TRIPOD_Z]
        target = [-0.3 * math.cos(a), -0.3 * math.sin(a), 1.1]
        cams.append(camera(len(cams), pos, target))
    return {"name": "stage24", "cameras": cams}


def scene():
    return {
        "pandora": 1,
        "units": "m",
        "materials": {
            "floor": {"color": [0.25, 0.25, 0.27]},
            "suit": {"color": [0.15, 0.15, 0.18]},
            "prop": {"color": [0.60, 0.45, 0.30]},
            "truss": {"color": [0.55, 0.55, 0.58]},
        },
        "objects": objects(),
        "rigs": [stage24()],
        "study": {
            "region": {"box": {"min": VOLUME_MIN, "max": VOLUME_MAX}},
            "voxel_size": 0.06,
            "fields": ["coverage", "cameras", "resolution", "sigma_max", "sigma_mean",
                       "triangulation_angle", "condition", "sigma_max_steady", "sigma_mean_steady"],
            "pixel_sigma": 0.2,
            # Performers: white acceleration of 20 m^2/s^3, 120 Hz capture.
            "motion": {"q": 20.0, "rate_hz": 120},
            "max_sigma_mm": 1.0,
        },
        "views": {
            "overview": {"from": [-6.5, -5.5, 4.8], "at": [0.0, 0.0, 0.9], "fov_deg": 55},
            "floor": {"from": [0.0, -5.0, 1.2], "at": [0.0, 0.0, 0.8], "fov_deg": 60},
        },
    }


with open(os.path.join(HERE, "scene.json"), "w") as f:
    json.dump(scene(), f, indent=1)
    f.write("\n")
print("wrote scene.json")
