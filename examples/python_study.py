"""A placement study in Python (docs/python.md): the mocap lab's two 12-camera rigs compared on the
share of the volume three cameras see and the triangulation error there, then a what-if: raise
one camera of the ring by 30 cm and aim it at the centre again, and see what changes; then ask
Pandora to nudge two cameras, look at the suggestion, apply it in memory, and accept it into a copy
of the scene file (the bundled example is never written).

Run after building (the module is built where pybind11 is installed, scripts/setup.sh):
    PYTHONPATH=build/python python3 examples/python_study.py
"""
import pathlib
import shutil
import tempfile

import numpy as np

import pandora

here = pathlib.Path(__file__).resolve().parent
scene = pandora.load_scene(str(here / "mocap_lab" / "scene.json"))
print(f"{scene.path}: rigs {', '.join(scene.rigs)}, voxel {scene.voxel_size} m")


def study(rig, label):
    fields = pandora.evaluate(scene, rig, ["coverage", "sigma_max"])
    _, xyz, coverage = fields.sparse("coverage")
    _, _, sigma = fields.sparse("sigma_max")
    share3 = float(np.mean(coverage >= 3))
    print(f"{label:>24}: >= 3 cameras {100 * share3:5.1f} %, sigma_max p50 {np.median(sigma):.3f} mm, "
          f"p90 {np.percentile(sigma, 90):.3f} mm over {len(sigma)} triangulable voxels")
    return xyz, coverage


for name in scene.rigs:
    study(scene.rig(name), name)

# What-if: the ring's first camera 30 cm higher, aimed again at the region's centre.
rig = scene.rig("ring")
first = rig.ids[0]
lo, hi = scene.region
centre = (lo + hi) / 2
raised = rig.position(first) + np.array([0.0, 0.0, 0.3])
rig.move(first, position=raised, look_at=centre)
xyz, coverage = study(rig, f"ring, {first} raised 0.3 m")

# Which cameras see the five least covered voxel centres, and how well they triangulate.
worst = np.argsort(coverage)[:5]
seen = pandora.visibility(scene, rig, xyz[worst])
cov = pandora.covariance(scene, rig, xyz[worst])
for i, p in enumerate(xyz[worst]):
    ids = [rig.ids[c] for c in np.flatnonzero(seen[i])]
    sigma = "not triangulable" if np.isnan(cov[i]).any() else f"{1000 * np.sqrt(np.linalg.eigvalsh(cov[i]).max()):.2f} mm"
    print(f"  voxel at {np.round(p, 2)}: seen by {ids or 'none'}, sigma_max {sigma}")

# Suggest: let the optimiser nudge the raised camera and its neighbour (30 cm, 15 degrees at most) to
# lower the 90th percentile of the triangulation error over target points. Nothing is written yet.
pick = rig.ids[:2]
s = pandora.suggest(scene, rig, pick, objective="sigma-p90", points=600, max_move=0.3, max_rotate_deg=15)
print(f"suggest {', '.join(pick)}: {s.message}")
for c in s.cameras:
    print(f"  {c['id']}: moves {100 * c['move_m']:.1f} cm, turns {c['rotate_deg']:.1f} deg")
if s.improved:
    s.apply()  # one undo step on the rig in memory
    study(rig, "after the suggestion")
    rig.undo()

# Accept into a copy of the scene file: the same code as `pandora accept` (backup, read-back check).
with tempfile.TemporaryDirectory() as tmp:
    copy = pathlib.Path(tmp) / "scene.json"
    shutil.copy(here / "mocap_lab" / "scene.json", copy)
    mine = pandora.load_scene(str(copy))
    ring = mine.rig("ring")
    s = pandora.suggest(mine, ring, pick, objective="sigma-p90", points=600, max_move=0.3, max_rotate_deg=15)
    if s.improved:
        r = s.accept()
        moved = np.linalg.norm(pandora.load_scene(str(copy)).rig("ring").position(pick[0]) - scene.rig("ring").position(pick[0]))
        print(f"accepted {', '.join(r['accepted'])} into a copy ({pick[0]} moved {100 * moved:.1f} cm; "
              f"backup {pathlib.Path(r['backup_path']).name})")
