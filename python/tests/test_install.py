"""`cmake --install` puts the package where Debian's python3 finds it for the prefix, and the
installed module finds the installed planners."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest


def test_installed_package_imports_and_finds_its_planners(tmp_path: Path) -> None:
    build = os.environ.get("VOXPLAN_BUILD_DIR")
    if not build:
        pytest.skip("VOXPLAN_BUILD_DIR not set (ctest sets it)")
    prefix = tmp_path / "prefix"
    proc = subprocess.run(["cmake", "--install", build, "--prefix", str(prefix), "--component",
                           "runtime"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    site = prefix / "lib" / version / "dist-packages"
    assert (site / "voxplan" / "_voxplan.pyi").is_file() and (site / "voxplan" / "py.typed").is_file()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VOXPLAN_PLANNER_PATH")}
    env["PYTHONPATH"] = str(site)
    code = ("import voxplan, json; print(json.dumps([voxplan.__file__, "
            "voxplan.planner_search_path(), voxplan.planners()]))")
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp_path,
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    file, search, planners = json.loads(out.stdout)
    assert Path(file).is_relative_to(site)
    assert search == [str(prefix / "lib" / "voxplan" / "planners")]
    assert "greedy" in planners
