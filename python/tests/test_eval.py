"""Meshes as arrays and files, and their evaluation against a known mesh."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import box_room_mesh

import voxplan


def square(z: float, size: float = 1.0) -> voxplan.Mesh:
    """A size x size square at height z (two triangles)."""
    v = np.array([[0, 0, z], [size, 0, z], [size, size, z], [0, size, z]], np.float32)
    return voxplan.Mesh(v, np.array([[0, 1, 2], [0, 2, 3]]))


def test_accuracy_and_completeness_of_a_shifted_square() -> None:
    gt = square(0.0)
    r = voxplan.evaluate_mesh(square(0.01), gt, threshold=0.05, samples_per_m2=20000)
    assert r["accuracy_mean_m"] == pytest.approx(0.01, abs=1e-5)
    assert r["accuracy_rms_m"] == pytest.approx(0.01, abs=1e-5)
    assert r["completeness"] == pytest.approx(1.0)
    assert r["ground_truth_area_m2"] == pytest.approx(1.0)
    tight = voxplan.evaluate_mesh(square(0.01), gt, threshold=0.005, samples_per_m2=20000)
    assert tight["completeness"] == 0.0
    # A reconstruction covering a quarter of the ground truth: completeness about a quarter.
    quarter = voxplan.evaluate_mesh(square(0.0, 0.5), gt, threshold=0.01, samples_per_m2=40000)
    assert quarter["completeness"] == pytest.approx(0.25, abs=0.02)
    assert quarter["accuracy_mean_m"] < 1e-6


def test_fused_room_against_its_mesh(room: Path) -> None:
    result = voxplan.fuse(room / "ds", voxel_size=0.05, trunc=0.2, max_depth=5.0)
    mesh = result.volume.extract_mesh()
    r = voxplan.evaluate_mesh(mesh, room / "room.ply", threshold=0.05, samples_per_m2=2000)
    assert r["accuracy_mean_m"] < 0.01  # noiseless depth: within a fifth of a voxel
    assert 0.3 < r["completeness"] < 1.0  # the walls all round, not the corners overhead
    assert r["ground_truth_area_m2"] == pytest.approx(2 * 16 + 4 * 10)


def test_mesh_files_round_trip(tmp_path: Path) -> None:
    mesh = box_room_mesh()
    for ext in ("ply", "obj", "glb"):
        mesh.save(tmp_path / f"room.{ext}")
        back = voxplan.read_mesh(tmp_path / f"room.{ext}")
        assert back.num_triangles == 12
        assert np.allclose(np.sort(back.vertices, axis=0), np.sort(mesh.vertices, axis=0))
    coloured = voxplan.Mesh(mesh.vertices, mesh.triangles,
                            colors=np.full((8, 3), 7, np.uint8), normals=np.ones((8, 3)))
    coloured.save(tmp_path / "c.ply")
    back = voxplan.read_mesh(tmp_path / "c.ply")
    assert back.colors is not None and (back.colors == 7).all()
    assert voxplan.read_mesh(tmp_path / "room.ply", scale=2.0).vertices.max() == pytest.approx(8.0)
