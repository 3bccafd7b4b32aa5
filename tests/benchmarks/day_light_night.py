#!/usr/bin/python3
"""What the day-light removal does to the night image (docs/rendering.md, "Albedo from the day image").

  day_light_night.py WORK_DIR SCENE_DIR...

Each SCENE_DIR is a `solo synth --day-render path` folder. For each, `solo night --seed 0`
(default preset) renders the scene without its albedo map three ways (the linearised day image,
`--remove-day-light --day-shadows-from-rays`, `--remove-day-light`) and once with the exact
albedo (gt/albedo.png). Printed: each way's mean absolute difference from the exact albedo's
night image in 8-bit sRGB codes over 4x4 pixel boxes (the box means take the sensor noise out),
and the removal's method from the report. The two manifests (no_albedo.json, exact_albedo.json)
are written beside each scene's own, whose relative paths they share; images and reports go to
WORK_DIR/<scene>/.
Environment: SOLO (the binary, build/release/tools/solo by default); the solo Python module is
read from the build's python/ folder beside it.
"""
import json
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SOLO = os.environ.get("SOLO", os.path.join(ROOT, "build", "release", "tools", "solo"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(SOLO)), "python"))
import solo  # noqa: E402

WAYS = [("day image", "no_albedo", []),
        ("shadow rays", "no_albedo", ["--remove-day-light", "--day-shadows-from-rays"]),
        ("image shadows", "no_albedo", ["--remove-day-light"]),
        ("exact albedo", "exact_albedo", [])]


def manifests(scene_dir):
    """The scene's manifest without its albedo map and with the exact one, beside the original."""
    with open(os.path.join(scene_dir, "scene.json")) as f:
        manifest = json.load(f)
    paths = {}
    for name, albedo in (("no_albedo", None), ("exact_albedo", "gt/albedo.png")):
        m = dict(manifest)
        m.pop("albedo", None)
        if albedo:
            m["albedo"] = albedo
        paths[name] = os.path.join(scene_dir, name + ".json")
        with open(paths[name], "w") as f:
            json.dump(m, f, indent=1)
    return paths


def box_means(image, box=4):
    h, w = image.shape[0] // box * box, image.shape[1] // box * box
    image = image[:h, :w].astype(np.float64)
    return image.reshape(h // box, box, w // box, box, -1).mean(axis=(1, 3))


def day_light_method(report_file):
    with open(report_file) as f:
        report = json.load(f)
    for stage in report["stages"]:
        if stage["name"] == "scene" and "day_light_method" in stage["metrics"]:
            return stage["metrics"]["day_light_method"]
    return "-"


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    work, scenes = argv[1], argv[2:]
    totals = {way: [] for way, _, _ in WAYS[:-1]}
    print("| scene | " + " | ".join(way for way, _, _ in WAYS[:-1]) + " | methods (rays, image) |")
    print("|---" * (len(WAYS) + 1) + "|")
    for scene_dir in scenes:
        name = os.path.basename(os.path.normpath(scene_dir))
        out = os.path.join(work, name)
        os.makedirs(out, exist_ok=True)
        paths = manifests(scene_dir)
        images = {}
        for way, manifest, flags in WAYS:
            stem = os.path.join(out, way.replace(" ", "_"))
            subprocess.run([SOLO, "night", paths[manifest], "--seed", "0", "-o", stem + ".png",
                            "--report", stem + ".json"] + flags, check=True, stdout=subprocess.DEVNULL)
            images[way] = (box_means(np.asarray(solo.read_image(stem + ".png"))), stem + ".json")
        exact = images["exact albedo"][0]
        cells = []
        for way, _, _ in WAYS[:-1]:
            mae = float(np.abs(images[way][0] - exact).mean())
            totals[way].append(mae)
            cells.append("%.2f" % mae)
        methods = ", ".join(day_light_method(images[w][1]) for w in ("shadow rays", "image shadows"))
        print("| %s | %s | %s |" % (name, " | ".join(cells), methods), flush=True)
    print("| mean | " + " | ".join("%.2f" % np.mean(v) for v in totals.values()) + " | |")


if __name__ == "__main__":
    main(sys.argv)
