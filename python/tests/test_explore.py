"""explore(): one short exploration run with a planner plugin, its metrics as a dict."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import voxplan


def test_explore_tiny_apartment(tmp_path: Path) -> None:
    assert "greedy" in voxplan.planners()
    progress: list[dict] = []
    result = voxplan.explore("apartment:size=R,seed=1", "greedy", robots=1, max_time=10.0,
                             out_dir=tmp_path / "run", threads=2, progress=progress.append)
    m = result.metrics
    assert result.terminated == "time_limit" and m["terminated"] == "time_limit"
    assert m["planner"] == "greedy" and m["robots"] == 1 and m["frames_fused"] > 0
    assert 0.0 < m["completeness"] <= 1.0 and m["time_s"] >= 10.0
    assert result.summary["completeness"] == m["completeness"] and "loop_ms" in result.summary
    # metrics.json in the output folder holds the same object.
    assert json.loads((tmp_path / "run" / "metrics.json").read_text()) == m
    assert (tmp_path / "run" / "mesh.ply").is_file() and result.out_dir == str(tmp_path / "run")
    assert result.mesh.num_triangles > 100 and result.volume is not None
    assert result.volume.num_blocks > 0 and result.planner_fault is None
    assert all({"t_s", "coverage", "frames_fused"} <= p.keys() for p in progress)


def test_explore_without_out_dir_and_refusals() -> None:
    result = voxplan.explore("apartment:size=R,seed=1", "greedy", robots=1, max_time=2.0,
                             threads=2)
    assert result.out_dir is None and result.metrics["frames_fused"] > 0
    with pytest.raises(FileNotFoundError, match="unknown planner 'nope'; available: .*greedy"):
        voxplan.explore("apartment:size=R,seed=1", "nope", max_time=1.0)
    with pytest.raises(ValueError, match="apartment"):
        voxplan.explore("apartment:size=Q", "greedy", max_time=1.0)


# --- every option of `voxplan explore` ---------------------------------------------------------
# Short runs (max_time 2: the start sweep and one plan call, about a second each) of one robot in
# the one-room apartment; each argument changes what the run does, or what it wrote.

APARTMENT = "apartment:size=R,seed=1"


def short_run(out_dir: Path | None = None, **kwargs: Any) -> voxplan.ExploreResult:
    kwargs.setdefault("max_time", 2.0)
    return voxplan.explore(kwargs.pop("scene", APARTMENT), kwargs.pop("planner", "greedy"),
                           robots=1, threads=2, out_dir=out_dir, **kwargs)


def robot_json(out_dir: Path) -> dict[str, Any]:
    return json.loads((out_dir / "robot.json").read_text())


@pytest.fixture(scope="module")
def baseline(tmp_path_factory: pytest.TempPathFactory) -> tuple[voxplan.ExploreResult, Path]:
    """A run with every new argument at its default, and its output folder."""
    out = tmp_path_factory.mktemp("explore") / "base"
    return short_run(out), out


@pytest.fixture(scope="module")
def moving() -> tuple[voxplan.ExploreResult, int]:
    """20 simulated seconds at the defaults (the robot drives off after the sweep), and how many
    progress calls it made."""
    progress: list[dict] = []
    result = short_run(max_time=20.0, progress=progress.append)
    assert result.metrics["distance_total_m"] > 0.5
    return result, len(progress)


def test_explore_camera_range_and_clearing(
        baseline: tuple[voxplan.ExploreResult, Path], tmp_path: Path) -> None:
    base, base_out = baseline
    assert robot_json(base_out)["explorer"]["max_range_m"] == 5.0  # the CLI's default
    assert not (base_out / "planner.png").exists()
    # A 1.5 m camera sees less of the room; planner.png drawn.
    near = short_run(tmp_path / "near", max_range=1.5, planner_picture=True)
    assert robot_json(tmp_path / "near")["explorer"]["max_range_m"] == 1.5
    assert near.metrics["completeness"] < base.metrics["completeness"]
    assert (tmp_path / "near" / "planner.png").is_file()
    # Depth beyond the range no longer clears the space in front of it.
    kept = short_run(max_range=1.5, clear_beyond_range=False)
    assert kept.metrics["coverage"] < near.metrics["coverage"]


def test_explore_fuse_steps_capture_and_progress(moving: tuple[voxplan.ExploreResult, int]) -> None:
    base, base_progress = moving
    frames = base.metrics["frames_fused"]
    # While driving: coarser steps fuse fewer frames, a capture rate captures on the clock.
    progress: list[dict] = []
    coarse = short_run(max_time=20.0, fuse_step=1.0, fuse_step_deg=90.0, progress_interval=1.0,
                       progress=progress.append)
    assert coarse.metrics["frames_fused"] < frames
    assert len(progress) > base_progress and len(progress) >= 3  # every simulated second
    assert short_run(max_time=20.0, capture_hz=5.0).metrics["frames_fused"] != frames


def test_explore_robot_config_and_field_of_view(tmp_path: Path) -> None:
    config = tmp_path / "robot.json"
    config.write_text(json.dumps({"explorer": {"max_range_m": 2.0, "horizontal_fov_deg": 60}}))
    # The file over the built-in robot; fov_deg, given, over the file.
    short_run(tmp_path / "run", robot_config=config, fov_deg=70.0, capture_hz=1.0)
    explorer = robot_json(tmp_path / "run")["explorer"]
    assert explorer["max_range_m"] == 2.0 and explorer["horizontal_fov_deg"] == 70.0
    assert explorer["capture_hz"] == 1.0
    assert robot_json(tmp_path / "run")["reconstructor"]["capture_hz"] == 1.0
    bad = tmp_path / "bad.json"
    bad.write_text('{"explorer": {"bogus": 1}}')
    with pytest.raises(ValueError, match="bad.json.*bogus"):
        short_run(robot_config=bad)
    with pytest.raises(FileNotFoundError, match="missing.json"):
        short_run(robot_config=tmp_path / "missing.json")


def test_explore_odometry_noise() -> None:
    # Tracked poses from the odometry prior: noisier odometry, another trajectory estimate (20 s:
    # the robot leaves the sweep, which anchors the map at the truth).
    clean = short_run(max_time=20.0, poses="tracked", odometry_noise=(0.0, 0.0))
    noisy = short_run(max_time=20.0, poses="tracked", odometry_noise=(0.2, 0.1))
    assert clean.metrics["distance_total_m"] > 0.5
    assert clean.metrics["ate_rms_m"] != noisy.metrics["ate_rms_m"]


@pytest.mark.filterwarnings("ignore:.*took longer than the budget")
def test_explore_planner_hard_limits() -> None:
    build = os.environ.get("VOXPLAN_BUILD_DIR")
    if not build:
        pytest.skip("VOXPLAN_BUILD_DIR not set (ctest sets it)")
    minimal = Path(build) / "tests" / "plugins" / "test_planners" / "libvoxplan_planner_minimal.so"
    if not minimal.is_file():
        pytest.skip(f"no test planner at {minimal}")
    # Its plan calls sleep 0.3 s; the hard limit is max(planner_hard_limit * plan_budget,
    # planner_hard_limit_min).
    slow = {"planner": str(minimal), "planner_config": {"sleep_ms": 300}, "plan_budget": 0.2,
            "planner_hard_limit": 1.0}
    assert short_run(**slow).terminated == "time_limit"  # max(0.2, 2) s
    with pytest.warns(voxplan.VoxplanWarning, match="hard limit of 0.200 s"):
        hung = short_run(**slow, planner_hard_limit_min=0.1)  # max(0.2, 0.1) s
    assert hung.terminated == "planner_hung" and "0.200 s" in hung.planner_fault
    slow["planner_hard_limit"] = 3.0
    assert short_run(**slow, planner_hard_limit_min=0.1).terminated == "time_limit"  # 0.6 s


def test_explore_scene_frame(baseline: tuple[voxplan.ExploreResult, Path], tmp_path: Path) -> None:
    # The apartment's world file, written again Y-up, and at half scale with its floor at 0.25.
    world = voxplan.read_mesh(baseline[1] / "world.ply")
    v, triangles = world.vertices, world.triangles
    voxplan.Mesh(v, triangles).save(tmp_path / "zup.ply")
    voxplan.Mesh(np.ascontiguousarray(np.stack([v[:, 0], v[:, 2], -v[:, 1]], 1)),
                 triangles).save(tmp_path / "yup.ply")
    half = v * np.float32(0.5) + np.array([0, 0, 0.25], np.float32)
    voxplan.Mesh(np.ascontiguousarray(half), triangles).save(tmp_path / "half.ply")
    zup = short_run(scene=str(tmp_path / "zup.ply"))
    yup = short_run(scene=str(tmp_path / "yup.ply"), up="y")
    # The same world, to the bit (a Y-up file is rotated exactly).
    assert yup.metrics["world_fingerprint"] == zup.metrics["world_fingerprint"]
    scaled = short_run(scene=str(tmp_path / "half.ply"), scale=2.0, floor_z=0.5)
    assert scaled.metrics["scene_floor_z_m"] == 0.5
    assert scaled.metrics["completeness"] == pytest.approx(zup.metrics["completeness"], abs=0.02)
    with pytest.raises(ValueError, match="wrong --scale or units"):
        short_run(scene=str(tmp_path / "half.ply"), scale=1000.0)


def test_explore_bounds_are_the_clis() -> None:
    cases = [
        ({"fov_deg": 180.0}, "fov_deg must lie strictly between 1 and 179 degrees, got 180"),
        ({"fov_deg": 1.0}, "fov_deg must lie strictly between 1 and 179"),
        ({"max_range": 0.1}, "max_range must be a finite number of metres above 0.1 and at most"),
        ({"max_range": float("nan")}, "max_range must be"),
        ({"capture_hz": 61.0}, "capture_hz must be 0 .* or a rate up to 60 frames per second"),
        ({"capture_hz": -1.0}, "capture_hz must be"),
        ({"planner_hard_limit": 0.5}, "planner_hard_limit must be a factor >= 1 of plan_budget"),
        ({"planner_hard_limit_min": 0.0}, "planner_hard_limit_min must be a finite number of sec"),
        ({"odometry_noise": (0.5, 2.0)},
         r"odometry_noise rotation \(per radian turned\) must be in \[0, 1\], got 2"),
        ({"odometry_noise": (1.5, 0.0)}, r"odometry_noise translation .* must be in \[0, 1\]"),
        ({"odometry_noise": (0.1,)}, r"odometry_noise must be \(translation per metre, rotation"),
        ({"fuse_step": 0.0}, r"fuse_step must be in \[1e-06, 1e\+06\] m, got 0"),
        ({"fuse_step_deg": -5.0}, r"fuse_step_deg must be in \[1e-06, 1e\+06\] degrees"),
        ({"progress_interval": 0.0}, r"progress_interval must be in \[1e-06, 1e\+06\] s"),
        ({"plan_budget": 0.0}, r"plan_budget must be in \[1e-06, 1e\+06\] s"),
        ({"planning_interval": 2e6}, r"planning_interval must be in \[1e-06, 1e\+06\] s"),
        ({"eval_samples": 0.0}, r"eval_samples must be in \[1e-06"),
        ({"up": "x"}, "up must be 'z' or 'y', got 'x'"),
        ({"scale": 0.0}, r"scale must be in \[1e-06, 1e\+06\], got 0"),
        ({"floor_z": 101.0}, r"floor_z must be 'auto' or a height in metres within \+-100, got 1"),
        ({"floor_z": "floor"}, "floor_z must be 'auto' or a height in metres"),
    ]
    for kwargs, message in cases:
        with pytest.raises(ValueError, match=message):
            short_run(**kwargs)
