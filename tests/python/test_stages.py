"""The stages on their own equal their commands: solo depth, solo lights, solo post."""

import json

import numpy as np

import solo
from conftest import run_cli


def test_refine_depth_is_solo_depth(solo_binary, default_dir, tmp_path):
    manifest = default_dir / "scene.json"
    run_cli(solo_binary, "depth", manifest, "-o", tmp_path / "refined.exr")
    refined = solo.refine_depth(solo.load_scene(manifest))
    assert np.array_equal(refined["depth"], solo.read_depth(tmp_path / "refined.exr"))
    assert np.array_equal(refined["uncertain"], solo.read_image(tmp_path / "refined.uncertain.png"))
    assert refined["report"]["command"] == "depth"
    assert [s["name"] for s in refined["report"]["stages"]][-1] == "refine"


def test_propose_lights_is_solo_lights(solo_binary, default_dir, tmp_path):
    manifest = default_dir / "scene.json"
    run_cli(solo_binary, "lights", manifest, "--seed", "3", "-o", tmp_path / "lights.json")
    proposed = solo.propose_lights(solo.load_scene(str(manifest)), seed=3)
    assert proposed["record"] == json.loads((tmp_path / "lights.json").read_text())
    assert proposed["record"] == solo.read_light_record(tmp_path / "lights.json")
    assert proposed["report"]["name"] == "lights"


def test_post_process_is_solo_post(solo_binary, default_dir, tmp_path):
    # a linear XYZ render: the night conversion's, as solo night --render-exr writes it
    result = solo.convert_night(solo.load_scene(default_dir / "scene.json"), preset="draft", seed=2)
    xyz = result["render"] / result["sensor_white_cd_m2"]
    solo.write_image(tmp_path / "render.exr", xyz)
    run_cli(solo_binary, "post", tmp_path / "render.exr", "-o", tmp_path / "post.png", "--seed", "5",
            "--stops", "3.25", "--noise-scale", "0.5")
    developed = solo.post_process(solo.read_image(tmp_path / "render.exr"), seed=5, stops=3.25, noise_scale=0.5)
    assert developed["image"].dtype == np.uint8
    assert np.array_equal(developed["image"], solo.read_image(tmp_path / "post.png"))
    assert [s["name"] for s in developed["report"]["stages"]][0] == "input"
