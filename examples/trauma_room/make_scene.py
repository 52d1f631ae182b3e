#!/usr/bin/env python3
"""Writes scene.json and scene_no_medics.json: the trauma room of State, Welch and Ilie (2006), Sec. 5.

A difficult-airway patient lies supine on a table (head toward +x), three medics crowd around him,
and two 8-camera rigs look at a region around his neck: `octagon`, a ring around and above the table
(paper Fig. 5), and `grid4x2`, a 4 x 2 grid looking down through the opening above the abdomen
(paper Fig. 6). Everything is built from primitives so the example needs no binary assets.

Run it after changing the parameters below; the JSON files it writes are committed.
Units: metres, world Z up.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def norm(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def add(a, b):
    return [x + y for x, y in zip(a, b)]


def scale(a, s):
    return [x * s for x in a]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def quat_z_to(d):
    """Quaternion [w, x, y, z] rotating +Z onto direction d."""
    d = norm(d)
    z = [0.0, 0.0, 1.0]
    c = dot(z, d)
    if c > 1 - 1e-12:
        return [1.0, 0.0, 0.0, 0.0]
    if c < -1 + 1e-12:
        return [0.0, 1.0, 0.0, 0.0]
    axis = cross(z, d)
    w = 1.0 + c
    q = [w, axis[0], axis[1], axis[2]]
    n = math.sqrt(sum(x * x for x in q))
    return [round(x / n, 9) for x in q]


def r3(v):
    return [round(x, 4) for x in v]


def limb(name, a, b, radius, material):
    """A capsule from point a to point b (the capsule's ends are rounded within the segment)."""
    d = sub(b, a)
    length = math.sqrt(dot(d, d))
    straight = max(0.01, length - 2 * radius)
    return {"name": name, "capsule": {"radius": radius, "length": round(straight, 4), "segments": 16},
            "position": r3(scale(add(a, b), 0.5)), "quaternion": quat_z_to(d),
            "material": material, "solid": True}


def person(name, feet, facing_deg, height, lean_deg, hands):
    """A standing person at `feet` (x, y), facing `facing_deg` (0 = +x), leaning forward by lean_deg
    from the hips, reaching with both hands to the points in `hands` (left, right)."""
    f = math.radians(facing_deg)
    fwd = [math.cos(f), math.sin(f), 0.0]
    left = [-math.sin(f), math.cos(f), 0.0]
    s = height / 1.75  # body proportions scale with height
    hip_z = 0.92 * s
    hip = [feet[0], feet[1], hip_z]
    lean = math.radians(lean_deg)
    up_t = norm(add(scale(fwd, math.sin(lean)), [0, 0, math.cos(lean)]))  # torso axis
    torso_len = 0.52 * s
    shoulder_c = add(hip, scale(up_t, torso_len))
    neck_top = add(shoulder_c, scale(up_t, 0.10 * s))
    head_c = add(neck_top, scale(up_t, 0.11 * s))
    objs = []
    for side, sgn in (("l", 1), ("r", -1)):
        foot = add([feet[0], feet[1], 0.05], scale(left, sgn * 0.11 * s))
        knee_hip = add(hip, scale(left, sgn * 0.10 * s))
        objs.append(limb(f"{name}/leg_{side}", foot, knee_hip, 0.07 * s, "scrubs"))
    objs.append(limb(f"{name}/torso", hip, shoulder_c, 0.17 * s, "scrubs"))
    objs.append(limb(f"{name}/shoulders", add(shoulder_c, scale(left, 0.19 * s)),
                     add(shoulder_c, scale(left, -0.19 * s)), 0.065 * s, "scrubs"))
    objs.append({"name": f"{name}/head", "sphere": {"radius": round(0.105 * s, 4), "segments": 24},
                 "position": r3(head_c), "material": "skin", "solid": True})
    for (side, sgn), hand in zip((("l", 1), ("r", -1)), hands):
        shoulder = add(shoulder_c, scale(left, sgn * 0.19 * s))
        # Elbow: halfway, dropped and pushed outward a little.
        elbow = add(scale(add(shoulder, hand), 0.5), add(scale(left, sgn * 0.08 * s), [0, 0, -0.10 * s]))
        objs.append(limb(f"{name}/upper_arm_{side}", shoulder, elbow, 0.045 * s, "scrubs"))
        objs.append(limb(f"{name}/forearm_{side}", elbow, hand, 0.038 * s, "glove"))
    return objs


TABLE_TOP = 0.90
NECK = [0.56, 0.0, 1.05]       # centre of the neck cylinder
REGION_MIN = [0.46, -0.11, 1.00]
REGION_MAX = [0.66, 0.11, 1.17]
TARGET = [0.56, 0.0, 1.08]     # where the cameras aim


def room(with_medics):
    objs = [
        {"name": "floor", "box": {"size": [6.0, 6.0, 0.05]}, "position": [0, 0, -0.025],
         "material": "floor", "solid": True},
        {"name": "table", "box": {"size": [2.0, 0.70, 0.10]}, "position": [0.0, 0.0, TABLE_TOP - 0.05],
         "material": "steel", "solid": True},
        {"name": "table_base", "box": {"size": [0.5, 0.4, TABLE_TOP - 0.10]},
         "position": [0.0, 0.0, (TABLE_TOP - 0.10) / 2], "material": "steel", "solid": True},
        # Patient, supine, head toward +x.
        limb("patient/torso", [-0.30, 0, 1.02], [0.36, 0, 1.02], 0.16, "gown"),
        limb("patient/leg_l", [-1.05, 0.10, 0.97], [-0.30, 0.09, 0.98], 0.075, "gown"),
        limb("patient/leg_r", [-1.05, -0.10, 0.97], [-0.30, -0.09, 0.98], 0.075, "gown"),
        limb("patient/arm_l", [-0.25, 0.23, 0.97], [0.30, 0.22, 1.00], 0.045, "skin"),
        limb("patient/arm_r", [-0.25, -0.23, 0.97], [0.30, -0.22, 1.00], 0.045, "skin"),
        {"name": "patient/neck", "cylinder": {"radius": 0.058, "height": 0.16, "segments": 32},
         "position": NECK, "quaternion": quat_z_to([1, 0, 0]), "material": "skin", "solid": True},
        # Head tilted back (airway extended).
        {"name": "patient/head", "sphere": {"radius": 0.10, "segments": 32},
         "position": [0.72, 0.0, 1.04], "material": "skin", "solid": True},
        {"name": "patient/chin", "sphere": {"radius": 0.045, "segments": 16},
         "position": [0.70, 0.0, 1.125], "material": "skin", "solid": True},
    ]
    if with_medics:
        # Airway doctor at the head end, leaning over the face.
        objs += person("medic_head", [1.15, 0.05], 180, 1.82, 32,
                       [[0.72, 0.10, 1.12], [0.70, -0.09, 1.13]])
        # Two medics at the sides of the neck and chest, reaching over the neck.
        objs += person("medic_left", [0.48, 0.66], -90, 1.68, 30,
                       [[0.60, 0.07, 1.14], [0.50, 0.05, 1.16]])
        objs += person("medic_right", [0.42, -0.66], 90, 1.88, 28,
                       [[0.49, -0.06, 1.15], [0.62, -0.08, 1.13]])
    return objs


PALETTE = ["#e6194b", "#3cb44b", "#4363d8", "#f58231", "#911eb4", "#42d4f4", "#f032e6", "#bfef45"]


def octagon():
    cams = []
    center = [0.30, 0.0]
    radius, height = 1.30, 2.05
    for i in range(8):
        a = math.radians(22.5 + 45 * i)
        pos = [center[0] + radius * math.cos(a), center[1] + radius * math.sin(a), height]
        cams.append({"id": f"o{i + 1}", "name": f"ring {i * 45 + 22.5:g} deg", "color": PALETTE[i],
                     "position": r3(pos), "look_at": TARGET, "up": [0, 0, 1],
                     "resolution": [1024, 768], "hfov_deg": 40,
                     "distortion": {"model": "brown_conrady", "k1": -0.08, "k2": 0.01},
                     "range": {"near": 0.3, "far": 4.0}})
    return {"name": "octagon", "cameras": cams}


def grid4x2():
    cams = []
    i = 0
    for row, z in enumerate((1.62, 1.84)):
        for col, y in enumerate((-0.27, -0.09, 0.09, 0.27)):
            pos = [-0.45, y, z]
            cams.append({"id": f"g{i + 1}", "name": f"grid r{row + 1} c{col + 1}", "color": PALETTE[i],
                         "position": pos, "look_at": TARGET, "up": [0, 0, 1],
                         "resolution": [1024, 768], "hfov_deg": 40,
                         "distortion": {"model": "brown_conrady", "k1": -0.08, "k2": 0.01},
                         "range": {"near": 0.3, "far": 4.0}})
            i += 1
    return {"name": "grid4x2", "cameras": cams}


def scene(with_medics):
    return {
        "pandora": 1,
        "units": "m",
        "materials": {
            "floor": {"color": [0.35, 0.35, 0.38]},
            "steel": {"color": [0.62, 0.64, 0.66]},
            "gown": {"color": [0.55, 0.70, 0.85]},
            "skin": {"color": [0.87, 0.68, 0.56]},
            "scrubs": {"color": [0.30, 0.55, 0.50]},
            "glove": {"color": [0.45, 0.55, 0.90]},
        },
        "objects": room(with_medics),
        "rigs": [octagon(), grid4x2()],
        "study": {
            "region": {"box": {"min": REGION_MIN, "max": REGION_MAX}},
            "voxel_size": 0.004,
            "fields": ["coverage", "cameras", "resolution", "sigma_max", "sigma_mean",
                       "triangulation_angle", "condition", "sigma_max_steady", "sigma_mean_steady"],
            "pixel_sigma": 0.5,
            # Hands and instruments at the neck: white acceleration of 1 m^2/s^3, 30 Hz video.
            "motion": {"q": 1.0, "rate_hz": 30},
            "max_sigma_mm": 2.0,
        },
        "views": {
            "overview": {"from": [-2.2, -2.4, 2.6], "at": [0.3, 0.0, 1.0], "fov_deg": 50},
            "neck": {"from": [0.1, -0.9, 1.7], "at": TARGET, "fov_deg": 40},
        },
    }


for fname, medics in (("scene.json", True), ("scene_no_medics.json", False)):
    with open(os.path.join(HERE, fname), "w") as f:
        json.dump(scene(medics), f, indent=1)
        f.write("\n")
    print("wrote", fname)
