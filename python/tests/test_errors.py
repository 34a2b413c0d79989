"""Errors raise Python exceptions carrying the library's messages."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import HEIGHT, PLANE_POSE, WIDTH, K, plane_depth

import voxplan


@pytest.fixture()
def depth() -> np.ndarray:
    return plane_depth(PLANE_POSE)


def test_wrong_dtype_and_shape(depth: np.ndarray) -> None:
    v = voxplan.Volume(0.02, 0.08)
    with pytest.raises(TypeError, match="float32 metres or uint16"):
        v.integrate(depth.astype(np.float64), None, K, PLANE_POSE)
    with pytest.raises(TypeError, match="give depth_scale"):
        v.integrate(depth.astype(np.uint16), None, K, PLANE_POSE)
    with pytest.raises(ValueError, match=r"depth must be an \(H, W\) array, got shape \(120, 160, 1\)"):
        v.integrate(depth[..., None], None, K, PLANE_POSE)
    with pytest.raises(TypeError, match="color must be uint8, got float32"):
        v.integrate(depth, np.zeros((HEIGHT, WIDTH, 3), np.float32), K, PLANE_POSE)
    with pytest.raises(ValueError, match="K must be a 3x3 matrix"):
        v.integrate(depth, None, np.eye(2), PLANE_POSE)
    with pytest.raises(ValueError, match="T_W_C must be a 4x4 matrix"):
        v.integrate(depth, None, K, np.eye(3))
    with pytest.raises(ValueError, match="points must be an \\(N, 3\\) array"):
        v.tsdf(np.zeros((4, 2)))
    assert v.num_blocks == 0  # nothing was fused


def test_library_messages(depth: np.ndarray) -> None:
    v = voxplan.Volume(0.02, 0.08)
    # IntegrateFrame's own refusals, word for word.
    with pytest.raises(ValueError, match="colour image size differs from the depth image size"):
        v.integrate(depth, np.zeros((HEIGHT, WIDTH - 1, 3), np.uint8), K, PLANE_POSE)
    bad = PLANE_POSE.copy()
    bad[:3, :3] *= 2.0
    with pytest.raises(ValueError, match="T_W_C: .*rotation"):
        v.integrate(depth, None, K, bad)
    with pytest.raises(ValueError, match="K: "):
        v.integrate(depth, None, [[0, 0, 80], [0, 120, 60], [0, 0, 1]], PLANE_POSE)
    v.max_depth = 0.0  # below min depth: IntegrateParams::Validate refuses it
    with pytest.raises(ValueError, match="depth"):
        v.integrate(depth, None, K, PLANE_POSE)
    with pytest.raises(ValueError, match="voxel"):
        voxplan.Volume(0.0, 0.04)
    with pytest.raises(ValueError, match="trunc"):
        voxplan.Volume(0.01, 1.0)


def test_files(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="missing.vpmap"):
        voxplan.Volume.load(tmp_path / "missing.vpmap")
    (tmp_path / "bad.vpmap").write_bytes(b"not a map at all, just some bytes to read")
    with pytest.raises(ValueError, match="bad.vpmap"):
        voxplan.Volume.load(tmp_path / "bad.vpmap")
    with pytest.raises(FileNotFoundError, match="no_such_dataset"):
        voxplan.open_dataset(tmp_path / "no_such_dataset")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="empty"):
        voxplan.open_dataset(tmp_path / "empty")
    with pytest.raises(FileNotFoundError, match="nothing.ply"):
        voxplan.read_mesh(tmp_path / "nothing.ply")
    (tmp_path / "broken.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n")
    with pytest.raises(ValueError, match="broken.ply"):
        voxplan.read_mesh(tmp_path / "broken.ply")
    with pytest.raises(ValueError, match="extension|unsupported|\\.xyz"):
        voxplan.Volume(0.02, 0.08).extract_mesh().save(tmp_path / "mesh.xyz")
