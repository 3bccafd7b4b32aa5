"""The night conversion from Python gives the image the solo binary gives for the same scene,
preset and seed: from arrays (scene_from_arrays) and from files (night)."""

import json

import numpy as np
import pytest

import solo
from conftest import run_cli

SEED = 7
PRESET = "draft"


@pytest.fixture(scope="module")
def cli_night(solo_binary, default_dir, tmp_path_factory):
    """`solo night` on the default scene: the image it writes, as an array."""
    out = tmp_path_factory.mktemp("cli") / "night.png"
    run_cli(solo_binary, "night", default_dir / "scene.json", "--preset", PRESET, "--seed", SEED, "-o", out)
    return solo.read_image(out)


def arrays_of(default_dir):
    """The default scene's maps as the files store them, and its camera."""
    manifest = json.loads((default_dir / "scene.json").read_text())
    return dict(
        image=solo.read_image(default_dir / manifest["image"]),
        depth=solo.read_depth(default_dir / manifest["depth"]),
        normals=solo.read_image(default_dir / manifest["normals"]),
        albedo=solo.read_image(default_dir / manifest["albedo"]),
        roughness=solo.read_image(default_dir / manifest["roughness"]),
        instances=solo.read_labels(default_dir / manifest["instances"]),
        labels=solo.read_labels(default_dir / manifest["labels"]),
        lights=solo.read_labels(default_dir / manifest["lights"]),
        light_groups=solo.read_labels(default_dir / manifest["light_groups"]),
        camera=manifest["camera"],
    )


def test_night_from_arrays_is_the_cli_image(cli_night, default_dir):
    arrays = arrays_of(default_dir)
    assert arrays["image"].dtype == np.uint8 and arrays["image"].shape == (540, 960, 3)
    scene = solo.scene_from_arrays(**arrays)
    loaded = solo.load_scene(default_dir / "scene.json")
    assert np.array_equal(scene.image, loaded.image)
    assert np.array_equal(scene.normals, loaded.normals)
    stages = []
    result = solo.convert_night(scene, preset=PRESET, seed=SEED, progress=lambda s, f: stages.append((s, f)))
    assert result["image"].dtype == np.uint8 and result["image"].shape == cli_night.shape
    assert np.array_equal(result["image"], cli_night)
    # what else the conversion hands back
    assert result["render"].shape == (540, 960, 3) and result["render"].dtype == np.float32
    assert set(result["aovs"]) >= {"albedo", "normal", "depth", "light_id"}
    assert result["refined_depth"].shape == (540, 960)
    assert result["lights"]["format"].startswith("solo-lights")
    assert result["report"]["seed"] == SEED and result["report"]["preset"] == PRESET
    assert [s["name"] for s in result["report"]["stages"]][-1] == "realism"
    assert result["realism"]["mean"] == pytest.approx(result["report"]["stages"][-1]["metrics"]["mean"])
    names = [s for s, _ in stages]
    assert names[0] == "refine" and "render" in names and names[-1] == "done"
    assert [f for _, f in stages] == sorted(f for _, f in stages)


def test_night_job_writes_the_cli_image(cli_night, default_dir, tmp_path):
    out = tmp_path / "night.png"
    report = solo.night(default_dir / "scene.json", out, preset=PRESET, seed=SEED)
    assert np.array_equal(solo.read_image(out), cli_night)
    assert (tmp_path / "night.report.json").exists()
    assert report["command"] == "night" and report["stages"][0]["name"] == "input"


def test_options_are_the_presets():
    draft = solo.night_options("draft")
    assert draft["max_spp"] == 2 and draft["render_downsample"] == 2
    default = solo.night_options()
    assert default["max_spp"] == 4 and default["light_sampler"] == "power" and default["seed"] == 0
    assert solo.night_options("draft", max_spp=3)["max_spp"] == 3
    assert solo.presets() == ["draft", "default", "final"]
    with pytest.raises(TypeError, match="no_such_option"):
        solo.night_options(no_such_option=1)
    with pytest.raises(TypeError, match="max_spp"):
        solo.night_options(max_spp=2.5)


def test_day_light_removal_options_match_the_cli(solo_binary, tmp_path):
    import subprocess

    default = solo.night_options()
    assert default["remove_day_light"] is False and default["day_shadows_from_image"] is True
    assert default["shading_normals"] is True
    config = tmp_path / "night.toml"
    subprocess.run([str(solo_binary), "night", "--remove-day-light", "--day-shadows-from-rays",
                    "--no-shading-normals", "--write-config", str(config)], check=True, capture_output=True)
    text = config.read_text()
    ours = solo.night_options(remove_day_light=True, day_shadows_from_image=False, shading_normals=False)
    for name in ("remove_day_light", "day_shadows_from_image", "shading_normals"):
        assert f"{name.replace('_', '-')} = {str(ours[name]).lower()}" in text


def test_bad_option_carries_the_cli_message(solo_binary, default_dir, tmp_path):
    from conftest import cli_error

    message = cli_error(solo_binary, "night", "--min-spp", "5", "--max-spp", "2", "-o", tmp_path / "cli.png")
    with pytest.raises(solo.InputError) as raised:
        solo.night(output=tmp_path / "py.png", min_spp=5, max_spp=2)
    assert str(raised.value) == message
    assert raised.value.file == "--min-spp"
    assert isinstance(raised.value, ValueError)
    assert list(tmp_path.iterdir()) == []
