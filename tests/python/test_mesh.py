"""Meshes as arrays: files round-trip, mesh cleanup and the mesh of a depth map equal the solo binary's."""

import numpy as np
import pytest

import solo
from conftest import run_cli


def sphere_with_hole(rings=8, segments=16, radius_m=1.0):
    """A closed UV sphere 4 m in front of the camera with two adjacent faces cut out: one small hole."""
    vertices = [(0.0, -radius_m, 4.0)]
    for r in range(1, rings):
        theta = np.pi * r / rings
        for s in range(segments):
            phi = 2 * np.pi * s / segments
            vertices.append((radius_m * np.sin(theta) * np.cos(phi), -radius_m * np.cos(theta),
                             4.0 + radius_m * np.sin(theta) * np.sin(phi)))
    vertices.append((0.0, radius_m, 4.0))
    ring = lambda r, s: 1 + (r - 1) * segments + s % segments
    bottom, top = 0, len(vertices) - 1
    faces = [(bottom, ring(1, s + 1), ring(1, s)) for s in range(segments)]
    for r in range(1, rings - 1):
        for s in range(segments):
            a, b, c, d = ring(r, s), ring(r, s + 1), ring(r + 1, s), ring(r + 1, s + 1)
            faces += [(a, b, d), (a, d, c)]
    faces += [(top, ring(rings - 1, s), ring(rings - 1, s + 1)) for s in range(segments)]
    del faces[segments + 4:segments + 6]  # one quad of the second ring
    return np.array(vertices), np.array(faces, dtype=np.uint32)


def test_mesh_file_round_trip(tmp_path):
    vertices, faces = sphere_with_hole()
    for ext in (".ply", ".obj", ".off"):
        solo.write_mesh(tmp_path / f"grid{ext}", vertices, faces)
        v, f = solo.read_mesh(tmp_path / f"grid{ext}")
        assert v.dtype == np.float64 and f.dtype == np.uint32
        assert np.array_equal(f, faces)
        assert np.allclose(v, vertices, atol=1e-6)


def test_clean_mesh_is_the_cli_mesh(solo_binary, tmp_path):
    vertices, faces = sphere_with_hole()
    solo.write_mesh(tmp_path / "in.ply", vertices, faces)
    run_cli(solo_binary, "mesh", "clean", tmp_path / "in.ply", "-o", tmp_path / "cli.ply")
    cli_vertices, cli_faces = solo.read_mesh(tmp_path / "cli.ply")
    v_in, f_in = solo.read_mesh(tmp_path / "in.ply")
    cleaned = solo.clean_mesh(v_in, f_in)
    assert len(cleaned["faces"]) > len(faces)  # the hole is filled
    assert cleaned["report"]["metrics"]["after_closed"] is True
    assert cleaned["report"]["name"] == "mesh clean"
    solo.write_mesh(tmp_path / "py.ply", cleaned["vertices"], cleaned["faces"])
    py_vertices, py_faces = solo.read_mesh(tmp_path / "py.ply")
    assert np.array_equal(py_faces, cli_faces)
    assert np.array_equal(py_vertices, cli_vertices)
    from_file = solo.clean_mesh(tmp_path / "in.ply")
    assert np.array_equal(from_file["faces"], cleaned["faces"])
    assert np.array_equal(from_file["vertices"], cleaned["vertices"])


def test_mesh_from_depth_is_the_cli_mesh(solo_binary, default_dir, tmp_path):
    run_cli(solo_binary, "mesh", "from-depth", default_dir / "scene.json", "-o", tmp_path / "cli.ply",
            "--no-evaluation")
    cli_vertices, cli_faces = solo.read_mesh(tmp_path / "cli.ply")
    mesh = solo.mesh_from_depth(solo.load_scene(default_dir / "scene.json"), evaluate=False)
    solo.write_mesh(tmp_path / "py.ply", mesh["vertices"], mesh["faces"])
    py_vertices, py_faces = solo.read_mesh(tmp_path / "py.ply")
    assert np.array_equal(py_faces, cli_faces)
    assert np.array_equal(py_vertices, cli_vertices)


def test_mesh_from_depth_array():
    depth = np.full((40, 60), 5.0, dtype=np.float32)
    camera = {"fx": 50.0, "fy": 50.0, "cx": 29.5, "cy": 19.5}
    mesh = solo.mesh_from_depth(depth=depth, camera=camera, solids=False, evaluate=False)
    assert mesh["vertices"].shape[1] == 3 and mesh["faces"].shape[1] == 3
    assert np.allclose(mesh["vertices"][:, 2], 5.0)
    with pytest.raises(solo.InputError, match="no 2x2 block"):
        solo.mesh_from_depth(depth=np.zeros((40, 60), np.float32), camera=camera)
    with pytest.raises(ValueError, match="faces"):
        solo.clean_mesh(np.zeros((3, 3)), np.array([[0, 1, 5]]))
