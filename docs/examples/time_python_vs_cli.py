#!/usr/bin/env python3
"""Time the night conversion of the default scene through the solo binary and through Python.

Alternates, REPEATS times each: `solo night` (a process: its wall time), `python3 -c "...
solo.night(...)"` (a process: import and the same job, files to files), and in this process
solo.night(...) and solo.load_scene + solo.convert_night (the call's wall time). Same preset and
seed everywhere. Prints the medians of wall time and of CPU time (user + system, all threads; less
sensitive to other work on the machine) and Python's extra cost against the binary.

    PYTHONPATH=build/release/python python3 docs/examples/time_python_vs_cli.py [--preset default] [--repeats 3]
"""

import argparse
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import solo

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cpu_seconds():
    """User + system time of this process and of its waited-for children, seconds."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def timed(function):
    """(wall, cpu) seconds of one call."""
    wall, cpu = time.perf_counter(), cpu_seconds()
    function()
    return time.perf_counter() - wall, cpu_seconds() - cpu


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
        runs["cli"].append(timed(lambda: subprocess.run(
            [str(args.binary), "night", "-o", str(out / "cli.png"), *common], check=True, capture_output=True)))
        runs["python process"].append(timed(lambda: subprocess.run(
            [sys.executable, "-c", script], check=True, capture_output=True, env=env)))
        runs["solo.night"].append(timed(lambda: solo.night(output=out / "py.png", preset=args.preset, seed=args.seed)))
        runs["convert_night"].append(timed(lambda: solo.convert_night(
            solo.load_scene(), preset=args.preset, seed=args.seed)))
    medians = {name: [statistics.median(t[k] for t in times) for k in (0, 1)] for name, times in runs.items()}
    print(f"solo {solo.__version__}, default scene, preset {args.preset}, seed {args.seed}, "
          f"median of {args.repeats}: wall s, CPU s (against the binary)")
    for name, (wall, cpu) in medians.items():
        against = "" if name == "cli" else (f"  ({100 * (wall / medians['cli'][0] - 1):+.1f} %, "
                                            f"{100 * (cpu / medians['cli'][1] - 1):+.1f} %)")
        walls = ", ".join(f"{t[0]:.2f}" for t in runs[name])
        print(f"  {name:<15} wall {wall:7.3f}  cpu {cpu:7.3f}{against}   walls: {walls}")


if __name__ == "__main__":
    main()
