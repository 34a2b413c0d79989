"""fuse(): the pipeline of `voxplan fuse`, byte for byte; the per-frame loop too; callbacks."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOM_FRAMES, run_cli

import voxplan

FRAMES, VOXEL, TRUNC = 20, 0.02, 0.08


@pytest.fixture(scope="module")
def icl(shared_data: Path) -> Path:
    return shared_data / "rgbd" / "iclnuim_office_traj0"


@pytest.fixture(scope="module")
def cli_outputs(cli: Path, icl: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("cli")
    run_cli(cli, "fuse", icl, "--frames", FRAMES, "--voxel-size", VOXEL, "--trunc", TRUNC,
            "--threads", 2, "--map", out / "cli.vpmap", "--mesh", out / "cli.ply",
            "--trajectory", out / "cli.txt", "--stats", out / "cli.json")
    return out


def test_fuse_equals_the_cli(icl: Path, cli_outputs: Path, tmp_path: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", voxplan.VoxplanWarning)
        ds = voxplan.open_dataset(icl)
        result = voxplan.fuse(ds, frames=FRAMES, voxel_size=VOXEL, trunc=TRUNC, threads=2)
    mesh = result.write(map=tmp_path / "py.vpmap", mesh=tmp_path / "py.ply",
                        trajectory=tmp_path / "py.txt")
    for ext in ("vpmap", "ply", "txt"):
        assert (tmp_path / f"py.{ext}").read_bytes() == (cli_outputs / f"cli.{ext}").read_bytes()
    assert mesh is not None and mesh.num_triangles > 1000
    cli_stats = json.loads((cli_outputs / "cli.json").read_text())
    stats = result.stats()
    for key in ("frames", "frames_selected", "frames_skipped", "frames_skipped_no_pose",
                "blocks", "voxels", "map_mb", "kernel", "threads", "depth_scale"):
        assert stats[key] == cli_stats[key], key
    assert result.frames == FRAMES - 1 and result.frames_skipped == 1  # frame id 1: no pose
    # ICL-NUIM's world is y-up: the dataset says so, the map records it, as the CLI's does.
    assert ds.up == "+y" and "ICL-NUIM" in ds.up_source
    assert result.volume.up == "+y" and cli_stats["up"] == "+y"
    assert voxplan.Volume.load(tmp_path / "py.vpmap").up == "+y"
    assert list(result.frame_indices) == list(range(1, FRAMES))
    assert result.poses.shape == (FRAMES - 1, 4, 4) and result.integrate_ms.shape == (FRAMES - 1,)
    # The volume is a Volume like any other: its mesh is the written one.
    assert np.array_equal(result.volume.extract_mesh().vertices, mesh.vertices)


def test_python_frame_loop_equals_the_cli(icl: Path, cli_outputs: Path, tmp_path: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", voxplan.VoxplanWarning)
        ds = voxplan.open_dataset(icl)
    volume = voxplan.Volume(VOXEL, TRUNC)
    for frame in ds.frames(count=FRAMES):
        if frame.T_W_C is not None:
            volume.integrate(frame.depth, frame.color, frame.K, frame.T_W_C)
    volume.up = ds.up  # what fuse records: the dataset's up axis
    volume.save(tmp_path / "loop.vpmap")
    assert (tmp_path / "loop.vpmap").read_bytes() == (cli_outputs / "cli.vpmap").read_bytes()


def test_progress_warnings_and_paths(room: Path) -> None:
    calls: list[tuple[int, int]] = []
    result = voxplan.fuse(room / "ds", voxel_size=0.05, trunc=0.2, max_depth=5.0, stride=2,
                          progress=lambda done, total: calls.append((done, total)))
    assert calls == [(k, ROOM_FRAMES // 2) for k in range(1, ROOM_FRAMES // 2 + 1)]
    assert result.frames == ROOM_FRAMES // 2 and list(result.frame_indices) == [0, 2, 4, 6]
    assert result.stats()["frames_selected"] == ROOM_FRAMES // 2


def test_an_exception_in_progress_stops_the_run(room: Path) -> None:
    calls = []

    def progress(done: int, total: int) -> None:
        calls.append(done)
        if done == 2:
            raise KeyError("stop here")

    with pytest.raises(KeyError, match="stop here"):
        voxplan.fuse(room / "ds", voxel_size=0.05, trunc=0.2, max_depth=5.0, progress=progress)
    assert calls == [1, 2]  # stopped after the frame that raised


def test_skipped_frames_warn(icl: Path) -> None:
    with pytest.warns(voxplan.VoxplanWarning, match="has no pose; skipped"):
        result = voxplan.fuse(icl, frames=3, voxel_size=0.04, trunc=0.16)
    assert any("no pose" in w for w in result.warnings)


def test_fuse_refusals(room: Path, icl: Path) -> None:
    ds = voxplan.open_dataset(room / "ds")
    with pytest.raises(ValueError, match="voxel"):
        voxplan.fuse(ds, voxel_size=0.0)
    with pytest.raises(ValueError, match="no frames selected"):
        voxplan.fuse(ds, start=100)
    with pytest.raises(ValueError, match="weighting"):
        voxplan.fuse(ds, weighting="linear")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", voxplan.VoxplanWarning)
        with pytest.raises(RuntimeError, match=r"no frame was integrated \(1 selected"):
            voxplan.fuse(icl, frames=1)  # ICL-NUIM's first frame has no pose
