"""`import pandora` (docs/python.md): the fields as numpy arrays agree with per-point visibility
(two code paths: the field evaluator and the visibility tester), dense and sparse forms agree, a
moved camera changes the fields of that rig copy only, the covariance equals a numpy computation
from finite-difference projection Jacobians, renders are finite images, and bad input raises
pandora.InputError with the file, JSON path and reason of the command line's message."""
import json
import math
import os
import pathlib

import numpy as np
import pytest

import pandora

SOURCE = pathlib.Path(os.environ.get("PANDORA_SOURCE", pathlib.Path(__file__).resolve().parents[2]))
MINIMAL = str(SOURCE / "tests" / "data" / "minimal.json")


def test_load_scene_and_rigs():
    scene = pandora.load_scene(MINIMAL)
    assert scene.rigs == ["pair"]
    assert scene.voxel_size == pytest.approx(0.05)
    lo, hi = scene.region
    np.testing.assert_allclose(lo, [-0.5, -0.5, 0.0])
    np.testing.assert_allclose(hi, [0.5, 0.5, 0.6])
    rig = scene.rig()
    assert rig.ids == ["a", "b"]
    np.testing.assert_allclose(rig.position("a"), [2, 0, 1])
    R = rig.rotation("a")
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    axis = np.array([0, 0, 0.3]) - np.array([2, 0, 1])
    np.testing.assert_allclose(R[:, 2], axis / np.linalg.norm(axis), atol=1e-12)
    k = rig.intrinsics("a")
    assert (k["width"], k["height"], k["model"]) == (640, 480, "pinhole")
    assert k["fx"] == pytest.approx(320 / np.tan(np.radians(30)))


def test_bad_input_raises_input_error_with_its_parts(tmp_path):
    text = json.loads(pathlib.Path(MINIMAL).read_text())
    text["rigs"][0]["cameras"][1]["hfov_deg"] = -5
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(text))
    with pytest.raises(pandora.InputError) as e:
        pandora.load_scene(str(bad))
    assert e.value.file == str(bad)
    assert e.value.path == "$.rigs[0].cameras[1].hfov_deg"
    assert e.value.reason
    assert str(bad) in str(e.value)
    scene = pandora.load_scene(MINIMAL)
    with pytest.raises(pandora.InputError):
        scene.rig("nope")
    with pytest.raises(pandora.InputError):
        pandora.visibility(scene, scene.rig(), np.array([[0.0, 0.0, np.nan]]))
    with pytest.raises(pandora.InputError):
        scene.rig().move("a", [1, 1, 1], [1, 1, 1])
    # Fields a script asks for are named as its keyword, not as the scene file's study.fields.
    with pytest.raises(pandora.InputError) as e:
        pandora.evaluate(scene, scene.rig(), ["coverage", "sigma_maxx"])
    assert e.value.file == "fields" and e.value.path == ""
    assert "sigma_maxx" in e.value.reason and "sigma_max" in e.value.hint


def test_coverage_equals_per_point_visibility():
    scene = pandora.load_scene(MINIMAL)
    rig = scene.rig()
    fields = pandora.evaluate(scene, rig, ["coverage", "resolution"])
    ijk, xyz, cov = fields.sparse("coverage")
    assert len(cov) > 1000
    seen = pandora.visibility(scene, rig, xyz)
    assert seen.shape == (len(cov), 2)
    np.testing.assert_array_equal(seen.sum(axis=1), cov)
    assert 0 < (cov == 2).sum() < len(cov)  # the block shadows part of the region
    assert fields.summary["region_voxels"] == len(cov)


def test_dense_and_sparse_agree():
    scene = pandora.load_scene(MINIMAL)
    fields = pandora.evaluate(scene, scene.rig(), ["coverage", "resolution"])
    for name in ("coverage", "resolution"):
        ijk, xyz, values = fields.sparse(name)
        dense = fields.dense(name)
        assert dense.shape == (20, 20, 12)
        np.testing.assert_array_equal(dense[ijk[:, 0], ijk[:, 1], ijk[:, 2]], values)
        assert np.isnan(dense).sum() == dense.size - len(values)
        # The voxel centres: the region's corner plus half a voxel, one voxel apart.
        np.testing.assert_allclose(xyz, -np.array([0.5, 0.5, 0.0]) + 0.025 + 0.05 * ijk, atol=1e-12)


def test_moving_a_camera_changes_that_rig_only():
    scene = pandora.load_scene(MINIMAL)
    rig = scene.rig()
    before = pandora.evaluate(scene, rig, ["coverage"]).sparse("coverage")[2]
    rig.move("b", [0, 2, 1], [0, 4, 1])  # looking away from the region
    after = pandora.evaluate(scene, rig, ["coverage"]).sparse("coverage")[2]
    assert after.max() == 1 and before.max() == 2
    again = pandora.evaluate(scene, scene.rig(), ["coverage"]).sparse("coverage")[2]
    np.testing.assert_array_equal(again, before)


def test_typed_edits_as_the_viewer_makes_them():
    scene = pandora.load_scene(MINIMAL)
    rig = scene.rig()
    k0 = rig.intrinsics("a")  # 640 x 480, hfov 60
    rig.zoom(["a", "b"], 90)  # fx = (w / 2) / tan(45 deg)
    assert rig.intrinsics("a")["fx"] == pytest.approx(320)
    assert rig.intrinsics("b")["fy"] / rig.intrinsics("b")["fx"] == pytest.approx(k0["fy"] / k0["fx"])
    rig.undo()
    rig.set_lens(["a"], model="fisheye", k1=0.01)  # the field of view kept: fx = (w / 2) / (hfov / 2)
    k = rig.intrinsics("a")
    assert k["model"] == "fisheye" and k["k"][0] == 0.01
    assert k["fx"] == pytest.approx(320 / (np.pi / 6))
    rig.set_lens(["a"], resolution=(320, 240))
    assert (rig.intrinsics("a")["width"], rig.intrinsics("a")["fx"]) == (320, pytest.approx(160 / (np.pi / 6)))
    rig.set_range(["a"], near=0.5, far=math.inf)
    assert (rig.intrinsics("a")["near"], rig.intrinsics("a")["far"]) == (0.5, math.inf)
    rig.set_color(["b"], [1, 0.5, 0])
    assert list(rig.intrinsics("b")["color"]) == [1, 0.5, 0]
    rig.orient("b", 90, 0)  # yaw 90 turns the base (+x) left, to +y
    assert rig.rotation("b")[:, 2] == pytest.approx([0, 1, 0], abs=1e-12)
    for call, keyword in [(lambda: rig.zoom(["a"], 0), "hfov_deg"),
                          (lambda: rig.set_range(["a"], near=2, far=1), "far"),
                          (lambda: rig.set_lens(["a"], model="pinhole", k4=0.1), "k4"),
                          (lambda: rig.set_color(["a"], [2, 0, 0]), "color"),
                          (lambda: rig.orient("a", 0, 95), "ypr_deg")]:
        with pytest.raises(pandora.InputError) as e:
            call()
        assert e.value.file == keyword, e.value


def project(R, C, k, X):
    p = R.T @ (X - C)
    return np.array([k["fx"] * p[0] / p[2] + k["cx"], k["fy"] * p[1] / p[2] + k["cy"]])


def test_covariance_equals_numpy_from_finite_differences():
    scene = pandora.load_scene(MINIMAL)
    rig = scene.rig()
    points = np.array([[0.3, -0.35, 0.5], [-0.4, 0.3, 0.45], [0.0, 0.0, 0.55]])
    cov = pandora.covariance(scene, rig, points)
    assert cov.shape == (3, 3, 3)
    sigma = 0.5  # the study's pixel noise
    for i, X in enumerate(points):
        J = np.zeros((3, 3))
        for cam in rig.ids:
            R, C, k = rig.rotation(cam), rig.position(cam), rig.intrinsics(cam)
            h = 1e-6
            A = np.column_stack([(project(R, C, k, X + h * e) - project(R, C, k, X - h * e)) / (2 * h) for e in np.eye(3)])
            J += A.T @ A / sigma**2
        np.testing.assert_allclose(cov[i], np.linalg.inv(J), rtol=1e-5, atol=1e-14)
    # A point only one camera sees: not triangulable, NaN.
    rig.set_enabled("b", False)
    assert np.isnan(pandora.covariance(scene, rig, points[:1])).all()


def test_render_is_a_finite_image():
    scene = pandora.load_scene(str(SOURCE / "examples" / "ptz_home" / "scene.json"))
    rig = scene.rig("home")
    img = pandora.render(scene, rig, width=160, height=100)
    assert img.shape == (100, 160, 3) and img.dtype == np.float32
    assert np.isfinite(img).all() and img.max() > 0
    plan = pandora.render(scene, rig, width=160, height=100, plan="plan")
    assert plan.shape == (100, 160, 3) and not np.array_equal(plan, img)


def test_render_options_as_keywords():
    """render() takes `pandora render`'s options: the grid pattern only takes light away (between
    its lines), light is linear in brightness, and a bad value names its keyword
    (RenderOptions::Check)."""
    scene = pandora.load_scene(str(SOURCE / "examples" / "ptz_home" / "scene.json"))
    rig = scene.rig("home")
    size = dict(width=320, height=200)
    uniform = pandora.render(scene, rig, **size)
    grid = pandora.render(scene, rig, pattern="grid", grid_pixels=64, **size)
    assert (grid <= uniform + 1e-6).all() and grid.sum() < 0.99 * uniform.sum()
    a, b, c = (pandora.render(scene, rig, brightness=x, **size) for x in (0.5, 1.0, 1.5))
    assert np.abs((c - b) - (b - a)).max() < 1e-5 * np.abs(c - b).max()
    assert not np.array_equal(pandora.render(scene, rig, surface="black", **size), uniform)
    for kwargs, keyword in [(dict(grid_pixels=0), "grid_pixels"), (dict(pattern="grd"), "pattern"),
                            (dict(samples=17), "samples"), (dict(brightness=-1), "brightness"),
                            (dict(surface="wire"), "surface")]:
        with pytest.raises(pandora.InputError) as e:
            pandora.render(scene, rig, width=16, height=10, **kwargs)
        assert e.value.file == keyword, (kwargs, str(e.value))
    with pytest.raises(pandora.InputError) as e:
        pandora.render(scene, rig, pattern="grd")
    assert "grid" in e.value.hint


def test_evaluate_returns_what_analyze_returns(tmp_path):
    """One conductor (app/session/analyze.h): evaluate's summary equals `pandora analyze`'s
    summary.json but for timings, on the mocap lab (people over six poses, body targets, pixel
    targets, N-1), and its grids include analyze's derived ones."""
    import subprocess

    binary = pathlib.Path(pandora.__file__).resolve().parent.parent / "pandora"
    scene_path = str(SOURCE / "examples" / "mocap_lab" / "scene.json")
    subprocess.run([str(binary), "analyze", scene_path, "--rig", "ring", "--out",
                    str(tmp_path / "out"), "--quiet"], check=True)
    analyzed = json.loads((tmp_path / "out" / "summary.json").read_text())
    scene = pandora.load_scene(scene_path)
    fields = pandora.evaluate(scene, scene.rig("ring"))

    def without_timings(d):
        if isinstance(d, dict):
            return {k: without_timings(v) for k, v in d.items()
                    if k not in ("timing", "run_id", "seconds", "parts_seconds")}
        if isinstance(d, list):
            return [without_timings(x) for x in d]
        return d

    expected, got = without_timings(analyzed), without_timings(fields.summary)
    for key in ("time", "targets", "pixel_targets", "robustness", "warnings"):
        assert key in got, key
    assert got == expected
    for grid in ("coverage_min", "coverage_time_share", "coverage_n1", "pixels_marker"):
        assert grid in fields.names, grid
