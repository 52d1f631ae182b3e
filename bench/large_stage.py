#!/usr/bin/env python3
"""Writes a generated large capture stage for the scale benchmarks (docs/performance.md, issue 15):
a 6 x 6 x 2.5 m region on a 10 x 10 m floor, a crowd of performers tessellated finely enough to
reach the asked triangle count, props, and cameras on a truss square and on tripods aimed into the
volume. Everything is a primitive of the scene format, so the file is small whatever the triangle
count.

    python3 bench/large_stage.py OUT.json [--triangles 1000000] [--cameras 24] [--performers 16]
                                          [--voxel 0.05] [--seed 1] [--motion]

The triangle count is met to within a few per cent (printed); the scene's own count is what
`pandora bench` prints.
"""
import argparse
import json
import math
import random

HALF = 3.0            # the region is [-3, 3] x [-3, 3] x [0.05, 2.55]
TRUSS_HALF = 4.6
TRUSS_Z = 3.6
TRIPOD_RADIUS = 4.4
TRIPOD_Z = 1.0


def r3(v):
    return [round(float(x), 4) for x in v]


def quat_z_to(d):
    n = math.sqrt(sum(x * x for x in d))
    d = [x / n for x in d]
    c = d[2]
    if c > 1 - 1e-12:
        return [1.0, 0.0, 0.0, 0.0]
    if c < -1 + 1e-12:
        return [0.0, 1.0, 0.0, 0.0]
    axis = [-d[1], d[0], 0.0]
    q = [1.0 + c] + axis
    n = math.sqrt(sum(x * x for x in q))
    return [round(x / n, 9) for x in q]


def sphere_tris(seg):
    stacks = max(2, seg // 2)
    return 2 * seg * (stacks - 1)


def capsule_tris(seg):
    stacks = max(1, seg // 4)
    return 2 * seg * (2 * stacks) + 2 * seg  # two hemispheres, their poles and the side


def performer_tris(seg):
    return 5 * capsule_tris(seg) + sphere_tris(seg)


def capsule(name, a, b, radius, seg):
    d = [y - x for x, y in zip(a, b)]
    length = math.sqrt(sum(x * x for x in d))
    return {"name": name, "capsule": {"radius": radius, "length": round(max(0.01, length - 2 * radius), 4),
                                      "segments": seg},
            "position": r3([(x + y) / 2 for x, y in zip(a, b)]), "quaternion": quat_z_to(d),
            "material": "suit", "solid": True}


def performer(name, x, y, facing_deg, height, arms_up, seg):
    f = math.radians(facing_deg)
    left = [-math.sin(f), math.cos(f), 0.0]
    s = height / 1.75
    hip = [x, y, 0.92 * s]
    shoulder = [x, y, 1.44 * s]
    objs = []
    for side, sgn in (("l", 1), ("r", -1)):
        foot = [x + sgn * 0.12 * s * left[0], y + sgn * 0.12 * s * left[1], 0.06]
        objs.append(capsule(f"{name}/leg_{side}", foot,
                            [hip[0] + sgn * 0.1 * s * left[0], hip[1] + sgn * 0.1 * s * left[1], hip[2]],
                            0.07 * s, seg))
        sh = [shoulder[0] + sgn * 0.19 * s * left[0], shoulder[1] + sgn * 0.19 * s * left[1], shoulder[2]]
        if arms_up:
            hand = [sh[0] + sgn * 0.15 * s * left[0], sh[1] + sgn * 0.15 * s * left[1], sh[2] + 0.62 * s]
        else:
            hand = [sh[0] + sgn * 0.68 * s * left[0], sh[1] + sgn * 0.68 * s * left[1], sh[2] - 0.02]
        objs.append(capsule(f"{name}/arm_{side}", sh, hand, 0.045 * s, seg))
    objs.append(capsule(f"{name}/torso", hip, shoulder, 0.16 * s, seg))
    objs.append({"name": f"{name}/head", "sphere": {"radius": round(0.105 * s, 4), "segments": seg},
                 "position": r3([x, y, 1.63 * s]), "material": "suit", "solid": True})
    return objs


def cameras(count):
    """Two thirds on the truss square (aimed across the volume), the rest on tripods (aimed up)."""
    palette = ["#e6194b", "#3cb44b", "#4363d8", "#f58231", "#911eb4", "#42d4f4", "#f032e6", "#bfef45",
               "#fabed4", "#469990", "#dcbeff", "#9a6324"]
    truss = max(1, (2 * count) // 3)
    out = []
    for i in range(count):
        if i < truss:
            t = (i + 0.5) / truss * 4  # position along the square's perimeter, in sides
            side, u = int(t), (t - int(t)) * 2 - 1
            outward = [(1, 0), (0, 1), (-1, 0), (0, -1)][side]
            tangent = [(0, 1), (-1, 0), (0, -1), (1, 0)][side]
            pos = [outward[0] * TRUSS_HALF + tangent[0] * u * TRUSS_HALF * 0.8,
                   outward[1] * TRUSS_HALF + tangent[1] * u * TRUSS_HALF * 0.8, TRUSS_Z]
            reach = 0.8 if i % 2 == 0 else -0.6
            target = [-outward[0] * reach - tangent[0] * 0.4 * u * HALF, -outward[1] * reach - tangent[1] * 0.4 * u * HALF,
                      0.9 + 0.2 * (i % 2)]
        else:
            a = 2 * math.pi * (i - truss + 0.5) / (count - truss)
            pos = [TRIPOD_RADIUS * math.cos(a), TRIPOD_RADIUS * math.sin(a), TRIPOD_Z]
            target = [-0.5 * math.cos(a), -0.5 * math.sin(a), 1.2]
        out.append({"id": f"c{i + 1:03d}", "color": palette[i % len(palette)], "position": r3(pos),
                    "look_at": r3(target), "up": [0, 0, 1], "resolution": [2048, 1536], "hfov_deg": 62,
                    "distortion": {"model": "brown_conrady", "k1": -0.06, "k2": 0.006},
                    "range": {"near": 0.5, "far": 14.0}})
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--triangles", type=int, default=1000000)
    ap.add_argument("--cameras", type=int, default=24)
    ap.add_argument("--performers", type=int, default=16)
    ap.add_argument("--voxel", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--motion", action="store_true",
                    help="add a motion model (study.motion), so that all nine fields can be asked for")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    fixed = 12 * 6  # floor and the six props' boxes
    per = max(1, (a.triangles - fixed) // max(1, a.performers))
    seg = 4
    while performer_tris(seg + 2) <= per:
        seg += 2
    objs = [{"name": "floor", "box": {"size": [10.0, 10.0, 0.05]}, "position": [0, 0, -0.025],
             "material": "floor", "solid": True}]
    for k in range(6):
        objs.append({"name": f"crate_{k + 1}", "box": {"size": [0.5, 0.5, 0.5 + 0.1 * k]},
                     "position": r3([rng.uniform(-2.6, 2.6), rng.uniform(-2.6, 2.6), (0.5 + 0.1 * k) / 2]),
                     "material": "prop", "solid": True})
    side = math.ceil(math.sqrt(a.performers))
    for p in range(a.performers):
        gx, gy = p % side, p // side
        x = -2.4 + 4.8 * (gx + 0.5) / side + rng.uniform(-0.2, 0.2)
        y = -2.4 + 4.8 * (gy + 0.5) / side + rng.uniform(-0.2, 0.2)
        objs += performer(f"performer_{p + 1:02d}", x, y, rng.uniform(0, 360), rng.uniform(1.6, 1.9),
                          p % 3 == 0, seg)
    scene = {
        "pandora": 1,
        "units": "m",
        "materials": {"floor": {"color": [0.25, 0.25, 0.27]}, "suit": {"color": [0.15, 0.15, 0.18]},
                      "prop": {"color": [0.6, 0.45, 0.3]}},
        "objects": objs,
        "rigs": [{"name": f"stage{a.cameras}", "cameras": cameras(a.cameras)}],
        "study": {"region": {"box": {"min": [-HALF, -HALF, 0.05], "max": [HALF, HALF, 2.55]}},
                  "voxel_size": a.voxel, "fields": ["coverage", "cameras", "resolution", "sigma_max"],
                  "pixel_sigma": 0.2},
        "views": {"overview": {"from": [-8.0, -7.0, 5.5], "at": [0.0, 0.0, 1.0], "fov_deg": 55}},
    }
    if a.motion:
        scene["study"]["motion"] = {"q": 20.0, "rate_hz": 120}
    with open(a.out, "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")
    total = fixed + a.performers * performer_tris(seg)
    print(f"{a.out}: {a.performers} performers at {seg} segments, about {total} triangles, "
          f"{a.cameras} cameras, voxel {a.voxel} m")


if __name__ == "__main__":
    main()
