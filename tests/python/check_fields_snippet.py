"""Checks the Python snippet of docs/fields.md: the docs show tests/python/fields_snippet.py
verbatim, and run on a fresh `pandora analyze` of tests/data/minimal.json it prints the numbers of
summary.json and, for its voxel, the number of per-camera grids active there (counted here
independently of the snippet).

Usage: /usr/bin/python3 check_fields_snippet.py PANDORA SOURCE_DIR OUT_DIR
"""
import json
import os
import re
import subprocess
import sys

import pyopenvdb as vdb

pandora, source, out = sys.argv[1:4]
snippet_path = os.path.join(source, "tests/python/fields_snippet.py")
with open(snippet_path) as f:
    snippet = f.read()
with open(os.path.join(source, "docs/fields.md")) as f:
    docs = f.read()
blocks = re.findall(r"```python\n(.*?)```", docs, re.S)
if snippet not in blocks:
    print("FAIL: docs/fields.md does not show tests/python/fields_snippet.py verbatim")
    sys.exit(1)

subprocess.run([pandora, "analyze", os.path.join(source, "tests/data/minimal.json"), "--out", out, "--quiet"],
               check=True)
path = os.path.join(out, "fields.vdb")
lines = subprocess.run([sys.executable, snippet_path, path], check=True, capture_output=True,
                       text=True).stdout.splitlines()
print("\n".join(lines))
with open(os.path.join(out, "summary.json")) as f:
    summary = json.load(f)
expected = [f"rig {summary['rig']} with {len(summary['per_camera'])} cameras; scene {summary['scene_sha256'][:12]}",
            f"free region voxels: {summary['region_voxels']}"]
expected += [f"camera {i} {c['id']!r} sees {c['visible_voxels']} voxels" for i, c in enumerate(summary["per_camera"])]
grids, _ = vdb.readAll(path)
ijk = (10, 10, 10)  # (0.025, 0.025, 0.525) is that voxel's centre: -0.475 + 0.05 * 10
seen = sum(g.getConstAccessor().isValueOn(ijk) for g in grids if g.name.startswith("visible/"))
expected.append(f"voxel {ijk} is seen by {seen} cameras")
if lines != expected:
    print("FAIL: the snippet printed something else than expected:\n" + "\n".join(expected))
    sys.exit(1)
print(f"ok: the docs' snippet prints the summary's numbers ({seen} cameras see voxel {ijk})")
