#!/usr/bin/env python3
"""Time the night conversion of the default scene through the solo binary and through Python.

Alternates, REPEATS times each: `solo night` (a process: its wall time), `python3 -c "...
solo.night(...)"` (a process: import and the same job, files to files), and in this process
solo.night(...) and solo.load_scene + solo.convert_night (the call's wall time). Same preset and
seed everywhere. Prints the medians and Python's extra cost against the binary.

    PYTHONPATH=build/release/python python3 docs/examples/time_python_vs_cli.py [--preset default] [--repeats 3]
"""

import argparse
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import solo

ROOT = pathlib.Path(__file__).resolve().parents[2]


def wall(function):
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", type=pathlib.Path, default=ROOT / "build" / "release" / "tools" / "solo")
    parser.add_argument("--preset", default="default")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    out = pathlib.Path(tempfile.mkdtemp(prefix="solo-timing-"))
    common = ["--preset", args.preset, "--seed", str(args.seed)]
    script = (f"import solo; solo.night(output={str(out / 'py_process.png')!r}, preset={args.preset!r}, "
              f"seed={args.seed})")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    runs = {"cli": [], "python process": [], "solo.night": [], "convert_night": []}
    for _ in range(args.repeats):
        runs["cli"].append(wall(lambda: subprocess.run(
            [str(args.binary), "night", "-o", str(out / "cli.png"), *common], check=True, capture_output=True)))
        runs["python process"].append(wall(lambda: subprocess.run(
            [sys.executable, "-c", script], check=True, capture_output=True, env=env)))
        runs["solo.night"].append(wall(lambda: solo.night(output=out / "py.png", preset=args.preset, seed=args.seed)))
        runs["convert_night"].append(wall(lambda: solo.convert_night(
            solo.load_scene(), preset=args.preset, seed=args.seed)))
    cli = statistics.median(runs["cli"])
    print(f"solo {solo.__version__}, default scene, preset {args.preset}, seed {args.seed}, "
          f"median of {args.repeats} (s)")
    for name, times in runs.items():
        median = statistics.median(times)
        extra = "" if name == "cli" else f"  {100 * (median / cli - 1):+.1f} % against the binary"
        print(f"  {name:<15} {median:7.3f}   ({', '.join(f'{t:.3f}' for t in times)}){extra}")


if __name__ == "__main__":
    main()
