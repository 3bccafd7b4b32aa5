"""Bad input raises the documented exception with the solo binary's message and writes nothing."""

import json

import numpy as np
import pytest

import solo
from conftest import cli_error


def test_missing_manifest(solo_binary, tmp_path):
    missing = tmp_path / "missing.json"
    message = cli_error(solo_binary, "info", missing)
    with pytest.raises(solo.MissingInputError) as raised:
        solo.load_scene(missing)
    assert isinstance(raised.value, FileNotFoundError) and isinstance(raised.value, solo.InputError)
    assert isinstance(raised.value, ValueError)
    assert str(raised.value) == message
    assert raised.value.file == str(missing)


def test_missing_map_writes_nothing(solo_binary, default_dir, tmp_path):
    manifest = json.loads((default_dir / "scene.json").read_text())
    manifest = {k: (str(default_dir / v) if isinstance(v, str) and k != "name" else v) for k, v in manifest.items()}
    manifest["depth"] = str(tmp_path / "no-depth.exr")
    (tmp_path / "scene.json").write_text(json.dumps(manifest))
    out = tmp_path / "out"
    out.mkdir()
    message = cli_error(solo_binary, "night", tmp_path / "scene.json", "-o", out / "cli.png")
    with pytest.raises(FileNotFoundError) as raised:
        solo.night(tmp_path / "scene.json", out / "py.png", preset="draft")
    assert str(raised.value) == message
    assert "no-depth.exr" in str(raised.value)
    assert list(out.iterdir()) == []


def test_bad_output_format_writes_nothing(solo_binary, tmp_path):
    message = cli_error(solo_binary, "night", "-o", tmp_path / "night.bmp")
    with pytest.raises(solo.InputError) as raised:
        solo.night(output=tmp_path / "night.bmp")
    assert str(raised.value) == message
    assert list(tmp_path.iterdir()) == []


def test_bad_arrays():
    image = np.zeros((20, 30, 3), np.uint8)
    depth = np.full((20, 30), 4.0, np.float32)
    with pytest.raises(solo.InputError, match="depth has no valid pixel"):
        solo.scene_from_arrays(image, np.zeros((20, 30), np.float32))
    with pytest.raises(ValueError, match="depth"):
        solo.scene_from_arrays(image, np.zeros((2, 20, 30, 1), np.float32))
    with pytest.raises(solo.InputError, match="light id 99"):
        solo.scene_from_arrays(image, depth, lights=np.full((20, 30), 99, np.int32))
    with pytest.raises(solo.InputError, match="camera"):
        solo.scene_from_arrays(image, depth, camera={"fx": -1.0, "fy": 1.0, "cx": 0.0, "cy": 0.0})
    scene = solo.scene_from_arrays(image, depth)
    assert scene.camera_is_default and scene.warnings
    depth[0, 0] = np.nan
    repaired = solo.scene_from_arrays(image, depth)
    assert repaired.depth[0, 0] == 0 and scene.describe()["metrics"]["depth_valid"] == 600


def test_scene_views_its_arrays():
    image = np.zeros((20, 30, 3), np.float32)
    depth = np.full((20, 30), 4.0, np.float32)
    scene = solo.scene_from_arrays(image, depth)
    depth[3, 4] = 7.0  # the scene views the array: no copy
    assert scene.depth[3, 4] == 7.0
    assert scene.image.base is not None


def test_int64_ids_are_taken():
    image = np.zeros((20, 30, 3), np.uint8)
    depth = np.full((20, 30), 4.0, np.float32)
    instances = np.full((20, 30), 26001, np.int64)  # numpy's default integer
    scene = solo.scene_from_arrays(image, depth, instances=instances)
    assert scene.instances.dtype == np.int32 and scene.labels[0, 0] == 26
    with pytest.raises(solo.InputError, match="instances"):
        solo.scene_from_arrays(image, depth, instances=np.full((20, 30), 2**40, np.int64))


def test_progress_can_stop_a_run(tmp_path):
    def stop(stage, fraction):
        if stage == "mesh":
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        solo.night(output=tmp_path / "night.png", preset="draft", progress=stop)
    assert list(tmp_path.iterdir()) == []
