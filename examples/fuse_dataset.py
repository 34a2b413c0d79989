#!/usr/bin/python3
"""Fuse an RGB-D dataset with voxplan from Python, write the mesh as a PLY, print some stats.

From the project root, after the README's setup (scripts/setup-deps, the build):

    PYTHONPATH=build/python examples/fuse_dataset.py \\
        ../shared/data/rgbd/iclnuim_office_traj0 out/icl_python.ply --voxel-size 0.01

`--loop` fuses frame by frame in Python (Volume.integrate on each Frame's numpy arrays)
instead of calling voxplan.fuse, the pipeline `voxplan fuse` runs; both give the same mesh.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import voxplan


def fuse_in_python(dataset: voxplan.Dataset, args: argparse.Namespace) -> voxplan.Volume:
    """The per-frame loop a Python user writes: every frame with a pose is integrated."""
    volume = voxplan.Volume(args.voxel_size, args.trunc, max_depth=args.max_depth)
    frames = dataset.frames(count=args.frames)
    for k, frame in enumerate(frames, 1):
        if frame.T_W_C is not None:
            volume.integrate(frame.depth, frame.color, frame.K, frame.T_W_C)
        if k % 20 == 0 or k == len(frames):
            print(f"\rfused {k}/{len(frames)} frames", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return volume


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dataset", help="an RGB-D dataset folder (TUM, ICL-NUIM, 7-Scenes, ...)")
    parser.add_argument("mesh", type=Path, help="the mesh to write (.ply, .obj, .glb, .stl)")
    parser.add_argument("--voxel-size", type=float, default=0.01, help="metres (default 0.01)")
    parser.add_argument("--trunc", type=float, default=0.04, help="metres (default 0.04)")
    parser.add_argument("--max-depth", type=float, default=3.0, help="metres (default 3)")
    parser.add_argument("--frames", type=int, default=0, help="frames to fuse (0: all)")
    parser.add_argument("--loop", action="store_true", help="integrate frame by frame in Python")
    args = parser.parse_args()

    t0 = time.perf_counter()
    dataset = voxplan.open_dataset(args.dataset)
    print(f"{dataset.format} dataset, {len(dataset)} frames of {dataset.width}x{dataset.height}, "
          f"depth scale {dataset.depth_scale:g}", file=sys.stderr)
    if args.loop:
        volume = fuse_in_python(dataset, args)
    else:
        def progress(done: int, total: int) -> None:
            if done % 20 == 0 or done == total:
                print(f"\rfused {done}/{total} frames", end="", file=sys.stderr, flush=True)

        result = voxplan.fuse(dataset, voxel_size=args.voxel_size, trunc=args.trunc,
                              max_depth=args.max_depth, frames=args.frames, progress=progress)
        print(file=sys.stderr)
        volume = result.volume
        stats = result.stats()
        print(f"{stats['frames']} frames integrated ({stats['frames_skipped']} skipped), "
              f"{stats['fps']} fps, integrate median {stats['integrate_ms_median']} ms")
    fuse_s = time.perf_counter() - t0

    mesh = volume.extract_mesh()
    args.mesh.parent.mkdir(parents=True, exist_ok=True)
    mesh.save(args.mesh)
    vertices = mesh.vertices  # (N, 3) float32, a view of the mesh's memory
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    print(f"map: {volume.num_blocks} blocks, {volume.memory_bytes / 2**20:.1f} MiB, "
          f"fused in {fuse_s:.2f} s")
    print(f"mesh: {mesh.num_vertices} vertices, {mesh.num_triangles} triangles -> {args.mesh}")
    print(f"extent: {np.round(lo, 2)} .. {np.round(hi, 2)} m, "
          f"mean colour {np.round(mesh.colors.mean(axis=0)) if mesh.colors is not None else None}")


if __name__ == "__main__":
    main()
