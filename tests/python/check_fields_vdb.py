"""Reads a fields.vdb written by `pandora analyze` with Debian's pyopenvdb and checks it against
the summary.json written beside it.

Run with Debian's Python (pyopenvdb is python3-openvdb; a pyenv `python3` lacks it):
  /usr/bin/python3 tests/python/check_fields_vdb.py PANDORA SCENE OUT_DIR [analyze options...]

It runs `pandora analyze SCENE --out OUT_DIR [options]`, then asserts, with pyopenvdb.readAll:
  - every grid reads (FloatGrid or BoolGrid only);
  - coverage holds whole numbers, its active voxels are the summary's free region voxels, its
    histogram is the summary's histogram, ge1 / ge2 / ge3 are the summary's fractions;
  - one BoolGrid "visible/<id>" per camera of the rig (id percent-encoded as docs/fields.md says)
    with camera_id and camera_index metadata; its active voxel count is the summary's
    visible_voxels and visible_fraction times the region voxels;
  - coverage equals the sum of the per-camera grids voxel for voxel (dense arrays over the box);
  - the float fields' active voxel counts are the summary's seen / triangulable voxel counts;
  - the file's metadata: scene_sha256 (recomputed from the scene file), rig_name, rig (JSON, the
    same camera ids in the same order), units, tool_version, and the transform: voxel size and
    voxel (0, 0, 0) at region.min + voxel_size / 2.
Prints "ok: ..." and exits 0, or prints FAIL and exits 1.
"""
import hashlib
import json
import os
import subprocess
import sys

import numpy as np
import pyopenvdb as vdb


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def expect(condition, message):
    if not condition:
        fail(message)


def close(a, b, tol=1e-12):
    return abs(a - b) <= tol * max(1.0, abs(a), abs(b))


def grid_name(camera_id):
    """VisibilityGridName (volume/vdb_check.h): bytes outside [A-Za-z0-9_.-] as %XX."""
    safe = set(b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.-")
    return "visible/" + "".join(chr(b) if b in safe else "%%%02X" % b for b in camera_id.encode())


def main():
    pandora, scene, out = sys.argv[1:4]
    subprocess.run([pandora, "analyze", scene, "--out", out, "--quiet"] + sys.argv[4:], check=True)
    path = os.path.join(out, "fields.vdb")
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)

    grids, meta = vdb.readAll(path)
    by_name = {g.name: g for g in grids}
    expect(len(by_name) == len(grids), "two grids share a name")
    for g in grids:
        expect(type(g).__name__ in ("FloatGrid", "BoolGrid"), f"grid {g.name} is a {type(g).__name__}")

    # File metadata: provenance.
    with open(scene, "rb") as f:
        sha = hashlib.sha256(f.read()).hexdigest()
    expect(meta.get("scene_sha256") == sha, f"scene_sha256 {meta.get('scene_sha256')} != {sha}")
    expect(meta.get("scene_sha256") == summary["scene_sha256"], "scene_sha256 differs from summary.json")
    expect(meta.get("rig_name") == summary["rig"], f"rig_name {meta.get('rig_name')} != {summary['rig']}")
    expect(meta.get("units") == "m", "units is not m")
    expect(meta.get("tool") == "pandora" and meta.get("tool_version"), "tool / tool_version missing")
    rig = json.loads(meta["rig"])
    ids = [c["id"] for c in rig["cameras"]]
    expect(rig["name"] == summary["rig"], "the rig JSON names another rig")
    expect(ids == [c["id"] for c in summary["per_camera"]], f"rig cameras {ids} differ from summary.json")

    # Transform: voxel size and voxel (0, 0, 0) at region.min + voxel_size / 2, the same for all.
    vs = summary["voxel_size_m"]
    lo = summary["region"]["min"]
    for g in grids:
        size = g.transform.voxelSize()
        expect(all(close(s, vs, 1e-9) for s in size), f"grid {g.name} voxel size {size} != {vs}")
        o = g.transform.indexToWorld((0, 0, 0))
        expect(all(close(o[a], lo[a] + vs / 2, 1e-9) for a in range(3)),
               f"grid {g.name}: voxel (0,0,0) at {o}, expected region.min + voxel_size / 2")

    # Coverage: whole numbers on every free region voxel.
    coverage = by_name.get("coverage")
    expect(coverage is not None and type(coverage).__name__ == "FloatGrid", "no FloatGrid 'coverage'")
    region_voxels = summary["region_voxels"]
    expect(coverage.activeVoxelCount() == region_voxels,
           f"coverage has {coverage.activeVoxelCount()} active voxels, summary.json {region_voxels}")
    (i0, j0, k0), (i1, j1, k1) = coverage.evalActiveVoxelBoundingBox()
    expect(min(i0, j0, k0) >= 0, "coverage has negative voxel indices")
    dims = (i1 + 1, j1 + 1, k1 + 1)
    expect(all(dims[a] <= summary["region"]["dims"][a] for a in range(3)), f"coverage spans {dims} voxels")
    cov = np.zeros(dims, dtype=np.float32)
    coverage.copyToArray(cov, ijk=(0, 0, 0))
    expect(np.all(cov == np.floor(cov)) and cov.min() >= 0, "coverage holds values that are not counts")
    # Histogram over the active voxels (tiles counted voxel by voxel).
    histogram = [0] * len(summary["coverage"]["histogram"])
    for item in coverage.citerOnValues():
        value = int(item["value"])
        expect(value == item["value"] and 0 <= value < len(histogram), f"coverage value {item['value']}")
        histogram[value] += item["count"]
    expect(histogram == summary["coverage"]["histogram"],
           f"coverage histogram {histogram} != summary.json {summary['coverage']['histogram']}")
    for k in (1, 2, 3):
        fraction = sum(histogram[k:]) / region_voxels
        expect(close(fraction, summary["coverage"][f"ge{k}"]),
               f"ge{k}: {fraction} from the grid, {summary['coverage'][f'ge{k}']} in summary.json")

    # One BoolGrid per camera; coverage is their sum voxel for voxel.
    total = np.zeros(dims, dtype=np.int64)
    for index, (camera_id, per_camera) in enumerate(zip(ids, summary["per_camera"])):
        name = grid_name(camera_id)
        g = by_name.get(name)
        expect(g is not None and type(g).__name__ == "BoolGrid", f"no BoolGrid {name!r} for camera {camera_id!r}")
        expect(g["camera_id"] == camera_id, f"{name}: camera_id {g['camera_id']!r}")
        expect(g["camera_index"] == index, f"{name}: camera_index {g['camera_index']} != {index}")
        count = g.activeVoxelCount()
        expect(count == per_camera["visible_voxels"],
               f"{name}: {count} active voxels, summary.json visible_voxels {per_camera['visible_voxels']}")
        expect(close(count / region_voxels, per_camera["visible_fraction"]),
               f"{name}: visible fraction {count / region_voxels} != {per_camera['visible_fraction']}")
        for item in g.citerOnValues():
            expect(item["value"] is True and item["count"] == 1, f"{name}: an active voxel that is not true")
        seen = np.zeros(dims, dtype=bool)
        g.copyToArray(seen, ijk=(0, 0, 0))
        expect(int(seen.sum()) == count, f"{name}: true voxels outside the coverage box or inactive")
        total += seen
    visible = [n for n in by_name if n.startswith("visible/")]
    expect(len(visible) == len(ids), f"{len(visible)} visible/ grids for {len(ids)} cameras")
    expect(np.array_equal(cov.astype(np.int64), total), "coverage differs from the sum of the camera grids")

    # Float fields: resolution where seen, uncertainty where triangulable.
    fields = summary["fields"]
    seen_voxels = int(np.count_nonzero(total))
    expect(seen_voxels == summary["active_voxels"], f"{seen_voxels} voxels seen, summary.json {summary['active_voxels']}")
    checked = ["coverage"] + [grid_name(i) for i in ids]
    for name in fields:
        if name in ("coverage", "cameras"):
            continue
        g = by_name.get(name)
        expect(g is not None and type(g).__name__ == "FloatGrid", f"no FloatGrid {name!r}")
        want = summary["active_voxels"] if name == "resolution" else summary["uncertainty"]["triangulable_voxels"]
        expect(g.activeVoxelCount() == want, f"{name}: {g.activeVoxelCount()} active voxels, expected {want}")
        for key in ("value_units", "description", "scene_sha256", "rig"):
            expect(key in g.metadata, f"{name}: no {key} metadata")
        checked.append(name)
    # N-1 (docs/failures.md): coverage after the worst single failure, max(coverage - 1, 0), on the
    # same voxels as coverage; written by analyze with the cameras field.
    n1 = by_name.get("coverage_n1")
    expect(n1 is not None and type(n1).__name__ == "FloatGrid", "no FloatGrid 'coverage_n1'")
    expect(n1.activeVoxelCount() == coverage.activeVoxelCount(),
           f"coverage_n1: {n1.activeVoxelCount()} active voxels, coverage {coverage.activeVoxelCount()}")
    after = np.zeros(dims, dtype=np.float32)
    n1.copyToArray(after, ijk=(0, 0, 0))
    expect(np.array_equal(after, np.maximum(cov - 1, 0)), "coverage_n1 differs from max(coverage - 1, 0)")
    checked.append("coverage_n1")
    expect(sorted(checked) == sorted(by_name), f"unexpected grids: {sorted(set(by_name) - set(checked))}")
    print(f"ok: pyopenvdb read {len(grids)} grids; coverage = sum of {len(ids)} camera grids on "
          f"{region_voxels} voxels; counts match summary.json")


if __name__ == "__main__":
    main()
