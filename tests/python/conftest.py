"""Shared fixtures of the Python module's tests: the solo binary, the default scene, temporary folders."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def solo_binary():
    """The solo binary the module is compared with: $SOLO_BINARY (set by ctest) or the release build's."""
    binary = pathlib.Path(os.environ.get("SOLO_BINARY", ROOT / "build" / "release" / "tools" / "solo"))
    if not binary.exists():
        pytest.skip(f"no solo binary at {binary}")
    return binary


@pytest.fixture(scope="session")
def default_dir():
    return ROOT / "data" / "default"


def run_cli(binary, *args, expect=0):
    """Runs the solo binary; returns (stdout, stderr) after checking its exit code."""
    done = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == expect, f"solo {' '.join(map(str, args))}: exit {done.returncode}\n{done.stderr}"
    return done.stdout, done.stderr


def cli_json(binary, *args):
    """The JSON a `solo ... --json` command prints."""
    stdout, _ = run_cli(binary, *args, "--json")
    return json.loads(stdout)


def cli_error(binary, *args):
    """The message `solo` prints for a run that fails with bad input (exit 2), without its prefix."""
    _, stderr = run_cli(binary, *args, expect=2)
    line = stderr.strip().splitlines()[-1]
    assert line.startswith("solo: error: "), stderr
    return line[len("solo: error: "):]
