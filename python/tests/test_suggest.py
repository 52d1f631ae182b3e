"""`import pandora`, suggest and accept (docs/python.md): a camera suggestion improves its exact
objective, apply() puts its poses on the rig, accept() writes them into the scene file (read back to
1e-9, backup equal to the old file, only the accepted camera changed); unsaved edits and a changed
file are refused; rig.save() writes a moved camera; PTZ settings, preset and tour suggestions
accepted and read back; PTZ fields from evaluate(); fields.write() read back with pyopenvdb; the
example script runs."""
import json
import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest

import pandora

SOURCE = pathlib.Path(os.environ.get("PANDORA_SOURCE", pathlib.Path(__file__).resolve().parents[2]))
RING = SOURCE / "tests" / "data" / "suggest_ring.json"
PTZ_HOME = SOURCE / "examples" / "ptz_home" / "scene.json"


def copy_scene(src, tmp_path):
    dst = tmp_path / "scene.json"
    shutil.copy(src, dst)
    return dst


def pose(rig, cid):
    return rig.position(cid), rig.rotation(cid)


def test_suggest_apply_accept_cycle(tmp_path):
    path = copy_scene(RING, tmp_path)
    original = path.read_text()
    scene = pandora.load_scene(str(path))
    rig = scene.rig()
    s = pandora.suggest(scene, rig, ["c2", "c4"], objective="coverage4", points=300, max_move=0.3,
                        max_rotate_deg=30)
    assert s.kind == "cameras" and s.improved
    assert s.after["objective"] > s.before["objective"]
    assert [c["id"] for c in s.cameras] == ["c2", "c4"]
    for c in s.cameras:
        assert c["move_m"] <= 0.3 + 1e-9 and c["rotate_deg"] <= 30 + 1e-9
    assert path.read_text() == original  # suggesting writes nothing
    d = s.to_dict()
    assert d["rig"] == rig.name and d["improved"] is True

    # Accept only c4: the file changes in c4's pose only, a backup keeps the old text.
    c2_before = pose(rig, "c2")
    result = s.accept(cameras=["c4"])
    assert result["accepted"] == ["c4"]
    assert pathlib.Path(result["backup_path"]).read_text() == original
    after = {c["id"]: c["after"] for c in s.cameras}
    np.testing.assert_allclose(rig.position("c4"), after["c4"][:3, 3], atol=1e-12)
    np.testing.assert_array_equal(rig.position("c2"), c2_before[0])
    assert rig.unsaved == []
    reread = pandora.load_scene(str(path)).rig()
    np.testing.assert_allclose(reread.position("c4"), after["c4"][:3, 3], atol=1e-9)
    np.testing.assert_allclose(reread.rotation("c4"), after["c4"][:3, :3], atol=1e-9)
    np.testing.assert_allclose(reread.position("c2"), c2_before[0], atol=1e-12)
    # The rest of the file is as it was (camera c4's pose keys aside).
    a, b = json.loads(original), json.loads(path.read_text())
    for j in (a, b):
        for k in ("position", "look_at", "up", "quaternion"):
            j["rigs"][0]["cameras"][3].pop(k, None)
    assert a == b

    # The same suggestion's c2 is now stale for the file: refused, nothing written.
    now = path.read_text()
    with pytest.raises(pandora.InputError) as e:
        s.accept(cameras=["c2"])
    assert "changed" in e.value.reason
    assert path.read_text() == now
    np.testing.assert_array_equal(rig.position("c2"), c2_before[0])  # the in-memory apply was undone


def test_apply_then_save_and_refusals(tmp_path):
    path = copy_scene(RING, tmp_path)
    original = path.read_text()
    scene = pandora.load_scene(str(path))
    rig = scene.rig()
    s = pandora.suggest(scene, rig, ["c2", "c4"], objective="coverage4", points=300, max_move=0.3, max_rotate_deg=30)
    assert s.improved
    s.apply()
    moved = [c["id"] for c in s.cameras if not np.array_equal(c["before"], c["after"])]
    assert moved
    for c in s.cameras:
        np.testing.assert_allclose(rig.position(c["id"]), c["after"][:3, 3], atol=1e-12)
    assert rig.unsaved == moved
    assert rig.undo() and rig.unsaved == [] and rig.redo() and rig.unsaved == moved
    # Unsaved edits: accept refuses (the file would not say what was optimised).
    with pytest.raises(pandora.InputError):
        s.accept()
    saved = rig.save()
    assert saved["saved"] == moved and pathlib.Path(saved["backup_path"]).read_text() == original
    reread = pandora.load_scene(str(path)).rig()
    for c in s.cameras:
        np.testing.assert_allclose(reread.position(c["id"]), c["after"][:3, 3], atol=1e-9)
        np.testing.assert_allclose(reread.rotation(c["id"]), c["after"][:3, :3], atol=1e-9)
    # A file changed by someone else is not overwritten without force.
    rig.move("c3", rig.position("c3") + [0, 0, 0.05], [0, 0, 0.5])
    path.write_text(path.read_text().replace('"voxel_size": 0.05', '"voxel_size": 0.050'))
    changed = path.read_text()
    with pytest.raises(pandora.InputError) as e:
        rig.save()
    assert "changed on disk" in e.value.reason
    assert path.read_text() == changed


def test_suggest_bad_options_name_the_keyword():
    scene = pandora.load_scene(str(RING))
    rig = scene.rig()
    cases = [
        (dict(cameras=["c1"], max_move=-1), "max_move"),
        (dict(cameras=["c1"], max_rotate_deg=[10, 20]), "max_rotate_deg"),
        (dict(cameras=["c1"], objective="coverage0"), "objective"),
        (dict(cameras=["nope"]), "cameras"),
        (dict(cameras=["c1"], hfov_range={"c1": (80, 10)}), "hfov_range"),
        (dict(cameras=["c1"], keep_out=[((0, 0, 0),)]), "keep_out"),
        (dict(cameras=["c1"], rail=(0, 0, 0)), "rail"),
        (dict(cameras=[]), "cameras"),
        (dict(cameras=["c1"], rail={"c2": (1, 0, 0)}), "rail"),  # c2 is not selected
        (dict(cameras=["c1"], mount_box=((0, 0, float("nan")), (1, 1, 1))), "mount_box"),
        (dict(cameras=["c1"], outer_iterations=0), "outer_iterations"),
        (dict(cameras=["c1"], snap_rotate_deg=200), "snap_rotate_deg"),
        (dict(cameras=["c1"], points=0), "points"),
    ]
    for kwargs, keyword in cases:
        with pytest.raises(pandora.InputError) as e:
            pandora.suggest(scene, rig, **{"points": 50, **kwargs})
        assert e.value.file == keyword, (kwargs, str(e.value))


def test_suggest_per_camera_limits_hold():
    # A list gives each selected camera its own limits, a dict mounts one camera: c2 may not move
    # at all, c4 only along its vertical rail, 0.3 m at most.
    scene = pandora.load_scene(str(RING))
    rig = scene.rig()
    start = {cid: pose(rig, cid) for cid in ["c2", "c4"]}
    s = pandora.suggest(scene, rig, ["c2", "c4"], objective="coverage4", points=300,
                        max_move=[0.0, 0.3], max_rotate_deg=[0, 30], rail={"c4": (0, 0, 1)})
    assert s.improved
    after = {c["id"]: c["after"] for c in s.cameras}
    np.testing.assert_allclose(after["c2"][:3, 3], start["c2"][0], atol=1e-12)
    np.testing.assert_allclose(after["c2"][:3, :3], start["c2"][1], atol=1e-12)
    d = after["c4"][:3, 3] - start["c4"][0]
    assert 0.01 < abs(d[2]) <= 0.3 + 1e-9
    np.testing.assert_allclose(d[:2], 0, atol=1e-9)


def test_suggestion_file_round_trip_through_accept(tmp_path):
    path = copy_scene(RING, tmp_path)
    scene = pandora.load_scene(str(path))
    s = pandora.suggest(scene, scene.rig(), ["c2", "c4"], objective="coverage4", points=300, max_rotate_deg=30)
    assert s.improved
    with pytest.raises(pandora.InputError):
        s.save(str(path))  # never over an input
    out = tmp_path / "suggestion.json"
    s.save(str(out))
    assert json.loads(out.read_text()) == s.to_dict()
    c4 = [c for c in s.cameras if c["id"] == "c4"][0]
    assert c4["move_m"] > 0 or c4["rotate_deg"] > 0
    r = pandora.accept(str(out), cameras=["c4"])
    assert r["accepted"] == ["c4"]
    reread = pandora.load_scene(str(path)).rig()
    np.testing.assert_allclose(reread.position("c4"), c4["after"][:3, 3], atol=1e-9)
    np.testing.assert_allclose(reread.rotation("c4"), c4["after"][:3, :3], atol=1e-9)
    np.testing.assert_array_equal(reread.position("c2"), scene.rig().position("c2"))


def test_ptz_settings_save_and_fields(tmp_path):
    path = copy_scene(PTZ_HOME, tmp_path)
    scene = pandora.load_scene(str(path))
    rig = scene.rig()
    p = rig.ptz("dome")
    assert [q["name"] for q in p["presets"]] == ["window", "west_door", "east_door"]
    assert [t["preset"] for t in p["tour"]] == ["window", "west_door", "window", "east_door"]
    assert p["hfov_deg"] == pytest.approx(30)
    # A PTZ camera's head follows a move, as in the viewer (app/session/camera_edits.h): the pivot
    # moves with the centre (this head has no offset) and pan and tilt face the target.
    rig.move("dome", [0, 0, 2], [0, 1, 1])
    assert rig.position("dome") == pytest.approx([0, 0, 2], abs=1e-9)
    assert rig.rotation("dome")[:, 2] == pytest.approx(np.array([0, 1, -1]) / np.sqrt(2), abs=1e-9)
    assert rig.unsaved == ["dome"]
    assert rig.undo()
    rig.set_ptz("dome", preset="west_door")
    q = rig.ptz("dome")
    assert (q["pan_deg"], q["tilt_deg"]) == pytest.approx((63, -3))
    assert q["hfov_deg"] == pytest.approx(40)
    # The camera's optical axis is the head's: pan about +z from home, tilt down 3 degrees.
    rig.set_ptz("dome", pan_deg=0, tilt_deg=0, hfov_deg=30)
    axis0 = rig.rotation("dome")[:, 2]
    rig.set_ptz("dome", pan_deg=90)
    axis = rig.rotation("dome")[:, 2]
    assert np.dot(axis0[:2], axis[:2]) == pytest.approx(0, abs=1e-12)
    rig.set_ptz("dome", tilt_deg=-500)  # clamped to the tilt range
    assert rig.ptz("dome")["tilt_deg"] == pytest.approx(-75)
    # A pinhole dome cannot zoom out to 200 degrees: refused, naming the keyword.
    with pytest.raises(pandora.InputError) as e:
        rig.set_ptz("dome", hfov_deg=200)
    assert e.value.file == "hfov_deg"
    rig.set_ptz("dome", pan_deg=20, tilt_deg=-10, hfov_deg=25)
    rig.save()
    again = pandora.load_scene(str(path)).rig().ptz("dome")
    assert (again["pan_deg"], again["tilt_deg"], again["hfov_deg"]) == pytest.approx((20, -10, 25), abs=1e-9)
    # evaluate() adds the PTZ fields as `pandora analyze` does.
    fields = pandora.evaluate(scene, rig, ["coverage"])
    assert "ptz_reach_time" in fields.names and "ptz_gap/dome" in fields.names
    _, _, reach = fields.sparse("ptz_reach_time")
    assert len(reach) > 0 and np.all(reach >= 0) and np.all(np.isfinite(reach))
    assert fields.summary["ptz"]["cameras"][0]["id"] == "dome"


def test_ptz_preset_and_tour_suggestions_accepted(tmp_path):
    path = copy_scene(PTZ_HOME, tmp_path)
    scene = pandora.load_scene(str(path))
    rig = scene.rig()
    s = pandora.suggest_ptz_preset(scene, rig, "dome", "west_door", points=300, target_region="west_door")
    assert s.kind == "ptz_preset"
    d = s.to_dict()
    if s.improved:
        s.accept()
        preset = [q for q in pandora.load_scene(str(path)).rig().ptz("dome")["presets"] if q["name"] == "west_door"][0]
        assert preset["pan_deg"] == pytest.approx(d["ptz"]["after"]["pan_deg"], abs=1e-9)
        assert preset["tilt_deg"] == pytest.approx(d["ptz"]["after"]["tilt_deg"], abs=1e-9)
        mine = [q for q in rig.ptz("dome")["presets"] if q["name"] == "west_door"][0]
        assert mine["pan_deg"] == pytest.approx(preset["pan_deg"], abs=1e-9)
    t = pandora.suggest_ptz_tour(scene, rig, "dome", points=300)
    assert t.kind == "ptz_tour"
    with pytest.raises(pandora.InputError):
        pandora.suggest_ptz_tour(scene, rig, "dome", objective="median")
    with pytest.raises(pandora.InputError):
        pandora.suggest_ptz_preset(scene, rig, "dome", "kitchen")


def test_fields_write_reads_back(tmp_path):
    openvdb = pytest.importorskip("pyopenvdb")
    scene = pandora.load_scene(str(RING))
    fields = pandora.evaluate(scene, scene.rig(), ["coverage", "resolution"])
    with pytest.raises(pandora.InputError):
        fields.write(str(RING))
    out = tmp_path / "fields.vdb"
    fields.write(str(out))
    grids = {g.name: g for g in openvdb.readAll(str(out))[0]}
    ijk, _, cov = fields.sparse("coverage")
    acc = grids["coverage"].getConstAccessor()
    got = np.array([acc.getValue(tuple(int(x) for x in c)) for c in ijk])
    np.testing.assert_array_equal(got, cov)
    assert grids["coverage"].activeVoxelCount() == len(cov)


def test_example_script_runs():
    env = dict(os.environ)
    bundled = (SOURCE / "examples" / "mocap_lab" / "scene.json").read_bytes()
    r = subprocess.run([sys.executable, str(SOURCE / "examples" / "python_study.py")], env=env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert any(">= 3 cameras" in l for l in lines), r.stdout
    assert any(l.startswith("suggest r1, r2: sigma-p90 improved") for l in lines), r.stdout
    assert any(l.startswith("accepted r1, r2 into a copy") for l in lines), r.stdout
    assert (SOURCE / "examples" / "mocap_lab" / "scene.json").read_bytes() == bundled  # never written
