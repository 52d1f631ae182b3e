#!/usr/bin/env python3
"""Exit 0 when two fields.vdb files hold the same grids voxel for voxel (names, active voxels,
values bit for bit, tiles expanded) and two summary.json files agree but for timings, run ids and
the MPI and stream blocks; else print the first difference and exit 1. A streamed run's folder
(`pandora analyze --stream`: no fields.vdb, the tiles listed in summary.json) counts as the union of
its tiles, which must not share a voxel.

    same_fields.py A_DIR B_DIR
"""
import json
import struct
import sys

import pyopenvdb as vdb

TIMING_KEYS = {"seconds", "merge_seconds", "parts_seconds", "run_id", "timing", "mpi", "cpu_seconds", "stream"}


def voxels(grid):
    out = {}
    for item in grid.citerOnValues():
        lo, hi = item.min, item.max
        v = item.value
        key = struct.pack("<f", v) if isinstance(v, float) else v
        for x in range(lo[0], hi[0] + 1):
            for y in range(lo[1], hi[1] + 1):
                for z in range(lo[2], hi[2] + 1):
                    out[(x, y, z)] = key
    return out


def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if k not in TIMING_KEYS}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x


def load(folder):
    """{grid name: {voxel: value}} of a folder's fields.vdb, or of the union of its streamed tiles."""
    summary = json.load(open(f"{folder}/summary.json"))
    if "stream" not in summary:
        return {g.name: voxels(g) for g in vdb.readAll(f"{folder}/fields.vdb")[0]}
    out = {}
    for tile in summary["stream"]["tiles"]:
        for g in vdb.readAll(f"{folder}/{tile['file']}")[0]:
            mine = voxels(g)
            into = out.setdefault(g.name, {})
            both = set(mine) & set(into)
            if both:
                sys.exit(f"grid {g.name}: voxel {next(iter(both))} in two tiles")
            into.update(mine)
    return out


def main():
    a_dir, b_dir = sys.argv[1], sys.argv[2]
    a, b = load(a_dir), load(b_dir)
    if sorted(a) != sorted(b):
        sys.exit(f"grids differ: {sorted(a)} vs {sorted(b)}")
    total = 0
    for name in sorted(a):
        va, vb = a[name], b[name]
        if va != vb:
            diff = next(k for k in set(va) | set(vb) if va.get(k) != vb.get(k))
            sys.exit(f"grid {name} differs at {diff}: {va.get(diff)} vs {vb.get(diff)}")
        total += len(va)
    sa = strip(json.load(open(f"{a_dir}/summary.json")))
    sb = strip(json.load(open(f"{b_dir}/summary.json")))
    if sa != sb:
        keys = [k for k in set(sa) | set(sb) if sa.get(k) != sb.get(k)]
        sys.exit(f"summaries differ in {keys}")
    print(f"same: {len(a)} grids, {total} active voxels, summaries equal but for timings")


if __name__ == "__main__":
    main()
