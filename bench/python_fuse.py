#!/usr/bin/python3
"""voxplan's Python API against `voxplan fuse` and Open3D's Python API, on the same frames.

Four ways to fuse frames start..start+N of one dataset, each timed in a fresh process:

  cli       `voxplan fuse DATASET --frames N ...` (its stats: loop_s, per-frame medians)
  py_fuse   voxplan.fuse(dataset, frames=N, ...): the same pipeline called from Python
  py_loop   for frame in dataset.frames(count=N): volume.integrate(frame.depth, frame.color,
            frame.K, frame.T_W_C) -- the loop a Python user writes (voxplan decodes)
  open3d    the same loop over Open3D's Python API: o3d.io.read_image (decode),
            RGBDImage.create_from_color_and_depth, ScalableTSDFVolume.integrate (RGB8), on the
            frames and poses `voxplan fuse --frame-list` lists (bench/open3d_fusion.py's legacy
            path; OMP_NUM_THREADS=threads, OMP_WAIT_POLICY=--omp-wait-policy)

Repeats are paired: each round runs every mode once, the order rotated round by round, so a
load change on a shared machine hits all modes alike. Per mode: loop_s (the frame loop:
decoding and integration, skipped frames included), integrate_ms (per integrated frame) and
decode_ms medians; medians over the rounds. Progress on stderr, one JSON object as the last
stdout line (and --json FILE).

    PYTHONPATH=build/python /usr/bin/python3 bench/python_fuse.py \\
        ../shared/data/rgbd/7scenes_redkitchen --frames 200 --repeat 5 --json py_7s.json
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
DEFAULT_CLI = HERE.parent / "build" / "apps" / "voxplan" / "voxplan"
MODES = ("cli", "py_fuse", "py_loop", "open3d")


def log(message: str) -> None:
    print("python_fuse.py: " + message, file=sys.stderr, flush=True)


def median(values: list[float]) -> float | None:
    return round(statistics.median(values), 4) if values else None


# --- workers (one process each) ---------------------------------------------------------------


def worker_py_fuse(args: argparse.Namespace) -> dict[str, Any]:
    import voxplan

    t0 = time.perf_counter()
    ds = voxplan.open_dataset(args.dataset)
    result = voxplan.fuse(ds, frames=args.frames, start=args.start, voxel_size=args.voxel_size,
                          trunc=args.trunc, max_depth=args.max_depth, threads=args.threads)
    wall = time.perf_counter() - t0
    stats = result.stats()
    return {"loop_s": result.loop_s, "wall_s": wall, "frames": result.frames,
            "integrate_ms_median": stats["integrate_ms_median"],
            "decode_ms_median": stats["load_ms_median"], "blocks": stats["blocks"]}


def worker_py_loop(args: argparse.Namespace) -> dict[str, Any]:
    import voxplan

    t0 = time.perf_counter()
    voxplan.set_threads(args.threads)
    ds = voxplan.open_dataset(args.dataset)
    volume = voxplan.Volume(args.voxel_size, args.trunc, max_depth=args.max_depth)
    integrate_ms, decode_ms = [], []
    loop_start = time.perf_counter()
    frames = ds.frames(start=args.start, count=args.frames)
    while True:
        t1 = time.perf_counter()
        frame = next(frames, None)
        if frame is None:
            break
        if frame.T_W_C is None:
            continue
        t2 = time.perf_counter()
        volume.integrate(frame.depth, frame.color, frame.K, frame.T_W_C)
        t3 = time.perf_counter()
        decode_ms.append((t2 - t1) * 1e3)
        integrate_ms.append((t3 - t2) * 1e3)
    end = time.perf_counter()
    return {"loop_s": end - loop_start, "wall_s": end - t0, "frames": len(integrate_ms),
            "integrate_ms_median": median(integrate_ms), "decode_ms_median": median(decode_ms),
            "blocks": volume.num_blocks}


def worker_open3d(args: argparse.Namespace) -> dict[str, Any]:
    import numpy as np
    import open3d as o3d

    t0 = time.perf_counter()
    with open(args.frame_list) as f:
        m = json.load(f)
    intr = o3d.camera.PinholeCameraIntrinsic(m["width"], m["height"], m["fx"], m["fy"], m["cx"],
                                             m["cy"])
    vol = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=m["voxel_size_m"], sdf_trunc=m["trunc_m"],
        color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
    integrate_ms, decode_ms = [], []
    loop_start = time.perf_counter()
    for f in m["frames"]:
        t1 = time.perf_counter()
        depth = o3d.io.read_image(f["depth"])
        color = o3d.io.read_image(f["color"])
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            color, depth, depth_scale=m["depth_scale"], depth_trunc=m["max_depth_m"],
            convert_rgb_to_intensity=False)
        extrinsic = np.linalg.inv(np.array(f["T_W_C"], dtype=np.float64).reshape(4, 4))
        t2 = time.perf_counter()
        vol.integrate(rgbd, intr, extrinsic)
        t3 = time.perf_counter()
        decode_ms.append((t2 - t1) * 1e3)
        integrate_ms.append((t3 - t2) * 1e3)
    end = time.perf_counter()
    return {"loop_s": end - loop_start, "wall_s": end - t0, "frames": len(integrate_ms),
            "integrate_ms_median": median(integrate_ms), "decode_ms_median": median(decode_ms),
            "open3d_version": o3d.__version__}


WORKERS = {"py_fuse": worker_py_fuse, "py_loop": worker_py_loop, "open3d": worker_open3d}


# --- the driver -------------------------------------------------------------------------------


def fuse_args(args: argparse.Namespace) -> list[str]:
    return [str(args.dataset), "--frames", str(args.frames), "--start", str(args.start),
            "--voxel-size", str(args.voxel_size), "--trunc", str(args.trunc),
            "--max-depth", str(args.max_depth), "--threads", str(args.threads)]


def run_cli(args: argparse.Namespace, tmp: Path) -> dict[str, Any]:
    stats_path = tmp / "cli_stats.json"
    t0 = time.perf_counter()
    subprocess.run([str(args.cli), "fuse", *fuse_args(args), "--stats", str(stats_path)],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    s = json.loads(stats_path.read_text())
    return {"loop_s": s["loop_s"], "wall_s": wall, "frames": s["frames"],
            "integrate_ms_median": s["integrate_ms_median"],
            "decode_ms_median": s["load_ms_median"], "blocks": s["blocks"]}


def run_worker(mode: str, args: argparse.Namespace) -> dict[str, Any]:
    env = dict(os.environ)
    if mode == "open3d":
        # ACTIVE keeps Open3D's OpenMP loops from stalling on an idle small machine (`voxplan
        # bench` sets it), but on a loaded one its spinning threads starve each other: 200
        # 7-Scenes frames took 147 s with ACTIVE, about 20 s with PASSIVE, at a load of 5.
        env.update(OMP_NUM_THREADS=str(args.threads),
                   OMP_WAIT_POLICY=args.omp_wait_policy.upper())
    cmd = [sys.executable, str(Path(__file__).resolve()), *sys.argv[1:], "--worker", mode,
           "--frame-list", str(args.frame_list)]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"python_fuse.py: the {mode} worker failed:\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dataset", type=Path)
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--start", type=int, default=0)
    parser.add_argument("--voxel-size", type=float, default=0.01)
    parser.add_argument("--trunc", type=float, default=0.04)
    parser.add_argument("--max-depth", type=float, default=3.0)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--modes", default=",".join(MODES),
                        help="comma-separated subset of " + ", ".join(MODES))
    parser.add_argument("--cli", type=Path, default=DEFAULT_CLI)
    parser.add_argument("--omp-wait-policy", choices=["active", "passive"], default="passive",
                        help="Open3D's OMP_WAIT_POLICY (default passive: see run_worker)")
    parser.add_argument("--json", type=Path, help="also write the result here")
    parser.add_argument("--worker", choices=sorted(WORKERS), help=argparse.SUPPRESS)
    parser.add_argument("--frame-list", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()

    if args.worker:
        print(json.dumps(WORKERS[args.worker](args)))
        return

    modes = [m for m in args.modes.split(",") if m]
    if unknown := set(modes) - set(MODES):
        sys.exit("python_fuse.py: unknown modes: " + ", ".join(sorted(unknown)))
    if "cli" in modes or "open3d" in modes:
        if not args.cli.is_file():
            sys.exit(f"python_fuse.py: no voxplan CLI at {args.cli} (--cli)")
    with tempfile.TemporaryDirectory(prefix="voxplan-pybench-") as tmp_name:
        tmp = Path(tmp_name)
        # The frames `voxplan fuse` integrates, for Open3D (outside every timing).
        args.frame_list = tmp / "frames.json"
        subprocess.run([str(args.cli), "fuse", *fuse_args(args), "--frame-list",
                        str(args.frame_list)], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        load_before = os.getloadavg()
        samples: dict[str, list[dict[str, Any]]] = {m: [] for m in modes}
        for r in range(args.repeat):
            order = modes[r % len(modes):] + modes[: r % len(modes)]
            for mode in order:
                s = run_cli(args, tmp) if mode == "cli" else run_worker(mode, args)
                samples[mode].append(s)
                log(f"round {r + 1}/{args.repeat} {mode}: loop {s['loop_s']:.3f} s, "
                    f"integrate {s['integrate_ms_median']} ms, decode {s['decode_ms_median']} ms")
        load_after = os.getloadavg()

    out: dict[str, Any] = {
        "command": "bench/python_fuse.py", "dataset": str(args.dataset), "frames": args.frames,
        "start": args.start, "voxel_size_m": args.voxel_size, "trunc_m": args.trunc,
        "max_depth_m": args.max_depth, "threads": args.threads, "repeat": args.repeat,
        "omp_wait_policy": args.omp_wait_policy,
        "order": "paired rounds, mode order rotated per round",
        "nproc": os.cpu_count(), "load_average_before": [round(x, 2) for x in load_before],
        "load_average_after": [round(x, 2) for x in load_after], "modes": {}}
    for mode, runs in samples.items():
        row: dict[str, Any] = {"frames": runs[0]["frames"]}
        for key in ("loop_s", "wall_s", "integrate_ms_median", "decode_ms_median"):
            values = [x[key] for x in runs if x[key] is not None]
            row[key if key.endswith("median") else key + "_median"] = median(values)
            row[key + "_runs"] = [round(v, 4) for v in values]
        if "open3d_version" in runs[0]:
            out["open3d_version"] = runs[0]["open3d_version"]
        out["modes"][mode] = row

    def ratio(a: str, b: str, key: str = "loop_s_median") -> float | None:
        if a in out["modes"] and b in out["modes"]:
            return round(out["modes"][a][key] / out["modes"][b][key], 3)
        return None

    out["ratios"] = {
        # > 1: the first is slower. The bar: py_loop / cli within 1.10.
        "py_loop_over_cli_loop": ratio("py_loop", "cli"),
        "py_fuse_over_cli_loop": ratio("py_fuse", "cli"),
        "open3d_over_py_loop": ratio("open3d", "py_loop"),
        "open3d_over_py_loop_integrate": ratio("open3d", "py_loop", "integrate_ms_median"),
        "py_loop_over_cli_integrate": ratio("py_loop", "cli", "integrate_ms_median"),
    }
    text = json.dumps(out)
    if args.json:
        args.json.write_text(json.dumps(out, indent=2) + "\n")
    print(text)


if __name__ == "__main__":
    main()
