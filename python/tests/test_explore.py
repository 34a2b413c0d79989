"""explore(): one short exploration run with a planner plugin, its metrics as a dict."""

from __future__ import annotations

import json
from pathlib import Path

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
