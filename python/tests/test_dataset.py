"""Datasets as iterables of frames: a sequence `voxplan sim render` writes, and a shared one."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOM_FRAMES

import voxplan


def test_rendered_sequence_iterates_as_frames(room: Path) -> None:
    ds = voxplan.open_dataset(room / "ds")
    assert (ds.format, len(ds), ds.width, ds.height) == ("tum", ROOM_FRAMES, 160, 120)
    assert ds.depth_scale == 5000 and ds.has_color
    assert np.allclose(ds.K, [[100, 0, 79.5], [0, 100, 59.5], [0, 0, 1]])
    frames = list(ds)
    assert [f.index for f in frames] == list(range(ROOM_FRAMES))
    assert np.allclose([f.timestamp for f in frames], np.arange(ROOM_FRAMES) * 0.1)
    for f in frames:
        assert f.depth.dtype == np.float32 and f.depth.shape == (120, 160)
        # The room is 4 x 4 x 2.5 m and the camera at its centre: every pixel sees a wall.
        assert (f.depth > 1.0).all() and (f.depth < 3.2).all()
        assert f.color is not None and f.color.shape == (120, 160, 3)
        assert f.color.dtype == np.uint8
        T = f.T_W_C
        assert T is not None and T.shape == (4, 4)
        assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-6)
        assert np.allclose(T[:3, 3], [2.0, 2.0, 1.2], atol=1e-6)
        assert np.array_equal(f.K, ds.K)
        # The arrays view the frame's decoded images.
        assert f.depth.base is f and f.color.base is f
    # Selections, negative indices, bounds.
    assert [f.index for f in ds.frames(start=1, stride=3)] == [1, 4, 7]
    assert len(ds.frames(count=2)) == 2
    assert ds[-1].index == ROOM_FRAMES - 1
    with pytest.raises(IndexError):
        ds[ROOM_FRAMES]
    assert str(room / "ds" / "depth.txt") in ds.input_files


def test_frames_integrate_in_place(room: Path) -> None:
    ds = voxplan.open_dataset(room / "ds")
    volume = voxplan.Volume(0.05, 0.2, max_depth=5.0)
    for frame in ds:
        stats = volume.integrate(frame.depth, frame.color, frame.K, frame.T_W_C)
        assert not stats["depth_copied"] and not stats["color_copied"]
    assert volume.num_blocks > 100


def test_shared_sequence_with_missing_pose(shared_data: Path) -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = voxplan.open_dataset(shared_data / "rgbd" / "iclnuim_office_traj0")
    assert any(issubclass(w.category, voxplan.VoxplanWarning) for w in caught)
    assert ds.format == "icl" and len(ds) == 200 and ds.K[1, 1] == -480.0
    first, second = ds[0], ds[1]
    assert first.T_W_C is None and second.T_W_C is not None
    assert first.depth_path.endswith("depth/1.png")
    assert 0.5 < float(np.median(second.depth[second.depth > 0])) < 5.0


def test_overrides(room: Path) -> None:
    ds = voxplan.open_dataset(room / "ds", intrinsics=(90.0, 90.0, 80.0, 60.0), depth_scale=2500)
    assert ds.K[0, 0] == 90.0 and ds.depth_scale == 2500
    # Half the scale doubles the depth.
    reference = voxplan.open_dataset(room / "ds")[0].depth
    assert np.allclose(ds[0].depth, 2 * reference, rtol=1e-6)


def test_prefetching_yields_the_same_frames(room: Path) -> None:
    ds = voxplan.open_dataset(room / "ds")
    plain = [f.depth.copy() for f in ds.frames(prefetch=0)]
    for prefetch in (1, 3, 16):
        frames = ds.frames(prefetch=prefetch)
        assert all(np.array_equal(a, f.depth) for a, f in zip(plain, frames, strict=True))
    # Leaving a loop early drops the frames decoded ahead; nothing is left running.
    for _ in range(20):
        it = iter(ds)
        next(it)
        del it
    with pytest.raises(ValueError, match="prefetch must be at most 64"):
        ds.frames(prefetch=65)
