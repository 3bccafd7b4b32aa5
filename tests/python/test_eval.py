"""Every evaluation from Python equals `solo eval ... --json` on the same files; arrays give the
same metrics as files."""

import numpy as np
import pytest

import solo
from conftest import cli_json


def without_seconds(record):
    return {k: v for k, v in record.items() if k != "seconds"}


@pytest.fixture(scope="module")
def maps(default_dir, tmp_path_factory):
    """A perturbed copy of the default scene's true depth and normals, as files."""
    folder = tmp_path_factory.mktemp("maps")
    gt_depth = solo.read_depth(default_dir / "gt" / "depth.exr")
    rng = np.random.default_rng(3)
    pred = (gt_depth * rng.uniform(0.9, 1.15, gt_depth.shape)).astype(np.float32)
    solo.write_depth(folder / "pred.exr", pred)
    normals = solo.read_normals(default_dir / "gt" / "normals.png")
    tilted = normals + rng.normal(0, 0.05, normals.shape).astype(np.float32)
    solo.write_image(folder / "normals.npy", tilted.astype(np.float32))
    return folder


def test_eval_depth(solo_binary, default_dir, maps):
    gt = default_dir / "gt" / "depth.exr"
    cli = cli_json(solo_binary, "eval", "depth", "--pred", maps / "pred.exr", "--gt", gt, "--max-depth", "80")
    py = solo.eval_depth(str(maps / "pred.exr"), gt, max_depth=80)
    assert without_seconds(py) == without_seconds(cli)
    arrays = solo.eval_depth(solo.read_depth(maps / "pred.exr"), solo.read_depth(gt), max_depth=80)
    for key, value in arrays["metrics"].items():
        assert value == cli["metrics"][key], key


def test_eval_normals(solo_binary, default_dir, maps):
    gt = default_dir / "gt" / "normals.png"
    cli = cli_json(solo_binary, "eval", "normals", "--pred", maps / "normals.npy", "--gt", gt)
    py = solo.eval_normals(maps / "normals.npy", gt)
    assert without_seconds(py) == without_seconds(cli)
    arrays = solo.eval_normals(solo.read_normals(maps / "normals.npy"), solo.read_normals(gt))
    for key, value in arrays["metrics"].items():
        assert value == cli["metrics"][key], key


def test_eval_mesh(solo_binary, default_dir):
    mesh = default_dir / "gt" / "mesh.ply"
    cli = cli_json(solo_binary, "eval", "mesh", mesh, "--ref", mesh, "--samples", "2000", "--seed", "4")
    py = solo.eval_mesh(mesh, ref=mesh, samples=2000, seed=4)
    assert without_seconds(py) == without_seconds(cli)
    arrays = solo.eval_mesh(solo.read_mesh(mesh), ref=mesh, samples=2000, seed=4)
    assert arrays["metrics"] == cli["metrics"]


def test_eval_scene(solo_binary, default_dir):
    cli = cli_json(solo_binary, "eval", "scene", default_dir, "--samples", "2000")
    py = solo.eval_scene(default_dir, samples=2000)
    assert without_seconds(py) == without_seconds(cli)


def test_eval_night(solo_binary, default_dir):
    day = default_dir / "day.png"
    cli = cli_json(solo_binary, "eval", "night", day)
    py = solo.eval_night([day])
    assert without_seconds(py) == without_seconds(cli)
    statistics = solo.night_statistics(solo.read_image(day))
    assert statistics == cli["images"][0]["statistics"] | {"width_px": 960, "height_px": 540}
