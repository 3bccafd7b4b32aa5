#!/usr/bin/env python3
"""Convert a folder of scenes to night with the solo Python module, then evaluate.

Every scene manifest under FOLDER (FOLDER/*/scene.json, e.g. streets made by `solo synth`) is
converted to a night image in OUT with a progress bar; then the night images are measured
against the real-night statistics (`solo eval night`), and where a scene has ground truth
(a `solo synth` folder) the refined depth is scored against it (`solo eval depth`).

    solo synth -o /tmp/streets/a --size 480x270 --seed 1
    solo synth -o /tmp/streets/b --size 480x270 --seed 2 --variant wide-sky
    PYTHONPATH=build/release/python python3 docs/examples/convert_folder.py /tmp/streets /tmp/night --preset draft
"""

import argparse
import json
import pathlib
import sys
import time

import numpy as np

import solo


def progress_bar(done, total, label, width=30):
    """One line redrawn in place: [#####-----] 3/8 label."""
    filled = int(width * done / total) if total else width
    sys.stderr.write(f"\r[{'#' * filled}{'-' * (width - filled)}] {int(done)}/{total} {label:<32.32}")
    sys.stderr.flush()


def convert(manifests, out_dir, preset, seed):
    """Each scene to OUT/<scene>.png; returns {scene name: conversion result}."""
    results = {}
    for i, manifest in enumerate(manifests):
        name = manifest.parent.name
        scene = solo.load_scene(manifest)

        def on_stage(stage, fraction, i=i, name=name):
            # the bar advances within a scene too: fraction is the share of its stages done
            progress_bar(i + fraction, len(manifests), f"{name}: {stage}")

        result = solo.convert_night(scene, preset=preset, seed=seed, progress=on_stage)
        solo.write_image(out_dir / f"{name}.png", result["image"])
        results[name] = result
        progress_bar(i + 1, len(manifests), name)
    sys.stderr.write("\n")
    return results


def evaluate(manifests, out_dir, results):
    """Realism of every night image, and the refined depth against ground truth where there is one."""
    realism = solo.eval_night([str(out_dir / f"{m.parent.name}.png") for m in manifests])
    print(f"{'scene':<16} {'mean luma':>9} {'clipped':>8} {'noise':>6} {'AbsRel est':>10} {'AbsRel refined':>14} {'s':>6}")
    for manifest, image in zip(manifests, realism["images"]):
        name = manifest.parent.name
        statistics = image["statistics"]
        result = results[name]
        abs_rel_est = abs_rel_refined = float("nan")
        truth = manifest.parent / "gt" / "depth.exr"
        if truth.exists():
            gt = solo.read_depth(truth)
            scene = solo.load_scene(manifest)
            estimated = scene.depth  # the network's depth, often at a lower resolution: nearest-upsampled
            rows = np.arange(gt.shape[0]) * estimated.shape[0] // gt.shape[0]
            cols = np.arange(gt.shape[1]) * estimated.shape[1] // gt.shape[1]
            abs_rel_est = solo.eval_depth(estimated[np.ix_(rows, cols)], gt)["metrics"]["abs_rel"]
            abs_rel_refined = solo.eval_depth(result["refined_depth"], gt)["metrics"]["abs_rel"]
        print(f"{name:<16} {statistics['mean']:>9.1f} {statistics['clipped']:>8.4f} "
              f"{statistics['noise'] or float('nan'):>6.2f} {abs_rel_est:>10.4f} {abs_rel_refined:>14.4f} "
              f"{result['report']['total_seconds']:>6.1f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=pathlib.Path, help="folder of scene folders (each with scene.json)")
    parser.add_argument("out", type=pathlib.Path, help="folder for the night images and summary.json")
    parser.add_argument("--preset", default="draft", choices=solo.presets())
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    manifests = sorted(args.folder.glob("*/scene.json"))
    if not manifests:
        sys.exit(f"no */scene.json under {args.folder}")
    args.out.mkdir(parents=True, exist_ok=True)
    print(f"solo {solo.__version__}: {len(manifests)} scenes, preset {args.preset}")
    start = time.perf_counter()
    results = convert(manifests, args.out, args.preset, args.seed)
    print(f"converted in {time.perf_counter() - start:.1f} s")
    evaluate(manifests, args.out, results)
    summary = {name: {"report": r["report"], "realism": r["realism"],
                      "lights_on": int(np.count_nonzero([l.get("on", False) for l in r["lights"].get("lights", [])]))}
               for name, r in results.items()}
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
