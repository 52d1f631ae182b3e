#!/usr/bin/env python3
"""Writes examples/lab_from_room/lab.dxf: the lab of scene.json as a CAD floor plan would draw it
(DXF, metres: $INSUNITS 6). Wall centre lines on layer "walls" (the room's footprint grown by half
the 0.15 m wall), a door line across the south wall and a window line across the east wall, the
door's swing as an arc (skipped by the import), and furniture outlines on one layer per height.

    pandora import-plan lab.dxf -o plan.json --furniture desks:0.75 --furniture chairs:0.9 \
        --furniture cabinets:1.9 --furniture racks:2.0 --height 3

gives the room of scene.json (docs/scene-format.md "Floor plans").

Usage: python3 examples/lab_from_room/make_plan.py  (rewrites lab.dxf next to this script)
"""
import os

X, Y = 3.5 + 0.075, 2.5 + 0.075  # wall centre lines


def rect(cx, cy, sx, sy):
    return [(cx - sx / 2, cy - sy / 2), (cx + sx / 2, cy - sy / 2), (cx + sx / 2, cy + sy / 2),
            (cx - sx / 2, cy + sy / 2)]


def main():
    out = []

    def g(code, value):
        out.append(f"{code}\n{value}")

    def lwpolyline(layer, points, closed):
        g(0, "LWPOLYLINE"), g(8, layer), g(90, len(points)), g(70, 1 if closed else 0)
        for x, y in points:
            g(10, round(x, 6)), g(20, round(y, 6))

    def line(layer, a, b):
        g(0, "LINE"), g(8, layer)
        g(10, a[0]), g(20, a[1]), g(30, 0), g(11, b[0]), g(21, b[1]), g(31, 0)

    g(0, "SECTION"), g(2, "HEADER"), g(9, "$INSUNITS"), g(70, 6), g(0, "ENDSEC")
    g(0, "SECTION"), g(2, "ENTITIES")
    lwpolyline("walls", [(-X, -Y), (X, -Y), (X, Y), (-X, Y)], True)
    line("doors", (-2.9, -Y), (-2.0, -Y))      # wall 0, 0.6 m from its start, 0.9 m wide
    line("windows", (X, -1.0), (X, 0.2))       # wall 1, 1.5 m from its start, 1.2 m wide
    g(0, "ARC"), g(8, "doors"), g(10, -2.9), g(20, -Y), g(30, 0), g(40, 0.9), g(50, 0), g(51, 90)
    lwpolyline("desks", rect(-2.6, 2.0, 1.6, 0.8), True)
    lwpolyline("chairs", rect(-2.6, 1.3, 0.5, 0.5), True)
    lwpolyline("cabinets", rect(3.0, 2.2, 0.8, 0.45), True)
    lwpolyline("racks", rect(-3.1, -1.2, 0.6, 1.0), True)
    g(0, "ENDSEC"), g(0, "EOF")
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "lab.dxf")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
