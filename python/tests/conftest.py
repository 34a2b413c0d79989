"""Fixtures of voxplan's pytest suite: the shared data, the CLI, analytic scenes and a small
rendered dataset. ctest runs the suite (python/CMakeLists.txt) with PYTHONPATH=build/python,
VOXPLAN_CLI and VOXPLAN_SHARED_DATA set; run by hand from the project root:

    PYTHONPATH=build/python python3 -m pytest -q python/tests
"""

from __future__ import annotations

import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import voxplan

REPO = Path(__file__).resolve().parents[2]


def shared_data_dir() -> Path:
    return Path(os.environ.get("VOXPLAN_SHARED_DATA", REPO.parent / "shared" / "data"))


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The shared real data (../shared/data); tests that need it skip without it."""
    path = shared_data_dir()
    if not (path / "rgbd").is_dir():
        pytest.skip(f"no shared data at {path}")
    return path


@pytest.fixture(scope="session")
def cli() -> Path:
    """The voxplan executable of this build."""
    path = Path(os.environ.get("VOXPLAN_CLI", REPO / "build" / "apps" / "voxplan" / "voxplan"))
    if not path.is_file():
        pytest.skip(f"no voxplan CLI at {path}")
    return path


def run_cli(cli: Path, *args: str | os.PathLike[str]) -> str:
    """Runs the CLI; returns stdout, failing the test with stderr when it fails."""
    proc = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


# --- an analytic plane ------------------------------------------------------------------------

WIDTH, HEIGHT = 160, 120
K = np.array([[120.0, 0.0, 79.5], [0.0, 120.0, 59.5], [0.0, 0.0, 1.0]])


def look_pose(eye: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """4x4 camera-to-world (OpenCV axes) at `eye` looking along `forward`, image up = world +z."""
    z = forward / np.linalg.norm(forward)
    x = np.cross(np.array([0.0, 0.0, -1.0]), z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, z, eye
    return T


# A camera 1 m in front of the wall x = 2 (looking along +x, slightly turned), so the wall's
# depth differs per pixel and a wrong pose shows.
PLANE_X = 2.0
PLANE_POSE = look_pose(np.array([1.0, 0.2, 1.1]), np.array([1.0, 0.15, -0.1]))


def plane_depth(T_W_C: np.ndarray, plane_x: float = PLANE_X) -> np.ndarray:
    """Depth (z along the optical axis, metres) of the plane x = plane_x seen from T_W_C."""
    u, v = np.meshgrid(np.arange(WIDTH), np.arange(HEIGHT))
    rays_c = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u, float)], -1)
    rays_w = rays_c @ T_W_C[:3, :3].T
    t = (plane_x - T_W_C[0, 3]) / rays_w[..., 0]  # z = t, since the ray's camera z is 1
    return np.where(t > 0, t, 0.0).astype(np.float32)


@pytest.fixture()
def plane_volume() -> voxplan.Volume:
    """A 2 cm volume with the plane fused from PLANE_POSE three times, in a uniform colour."""
    volume = voxplan.Volume(0.02, 0.08)
    depth = plane_depth(PLANE_POSE)
    color = np.zeros((HEIGHT, WIDTH, 4), np.uint8)
    color[..., :3] = (200, 100, 50)
    for _ in range(3):
        volume.integrate(depth, color, K, PLANE_POSE)
    return volume


# --- a small rendered dataset -------------------------------------------------------------------


def box_room_mesh(size: tuple[float, float, float] = (4.0, 4.0, 2.5)) -> voxplan.Mesh:
    """A closed box room from the origin to `size` (12 triangles)."""
    sx, sy, sz = size
    vertices = np.array(
        [[x, y, z] for z in (0.0, sz) for y in (0.0, sy) for x in (0.0, sx)], np.float32
    )
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    return voxplan.Mesh(vertices, np.array(triangles))


def quaternion(R: np.ndarray) -> tuple[float, float, float, float]:
    """(qx, qy, qz, qw) of a rotation matrix."""
    w = math.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    return x, y, z, w


ROOM_FRAMES = 8


@pytest.fixture(scope="session")
def room(cli: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A TUM-layout dataset `voxplan sim render` renders (noise off, 160x120) in a box room:
    ROOM_FRAMES views turning round at the room's centre. The folder holds room.ply too."""
    folder = tmp_path_factory.mktemp("room")
    box_room_mesh().save(folder / "room.ply")
    with open(folder / "traj.txt", "w") as f:
        for i, a in enumerate(np.linspace(0, 2 * np.pi, ROOM_FRAMES, endpoint=False)):
            T = look_pose(np.array([2.0, 2.0, 1.2]), np.array([math.cos(a), math.sin(a), -0.2]))
            qx, qy, qz, qw = quaternion(T[:3, :3])
            f.write(f"{i * 0.1:.3f} 2.0 2.0 1.2 {qx:.9f} {qy:.9f} {qz:.9f} {qw:.9f}\n")
    run_cli(cli, "sim", "render", "--scene", folder / "room.ply", "--trajectory",
            folder / "traj.txt", "--out", folder / "ds", "--size", "160x120", "--fx", "100",
            "--noise", "off", "--no-labels", "--threads", "2")
    return folder
