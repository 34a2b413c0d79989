#!/usr/bin/python3
"""Open3D reference timings for voxplan's fusion benchmarks.

Reads the frame list that `voxplan fuse --frame-list F.json` writes (intrinsics, depth scale,
parameters, and the integrated frames: depth/colour paths and row-major 4x4 camera-to-world
poses), decodes every image first, then times integration only with
Open3D's legacy ScalableTSDFVolume and its CPU VoxelBlockGrid on identical frames and
parameters. Prints one JSON object. Run it with OMP_WAIT_POLICY=ACTIVE and OMP_NUM_THREADS set,
or Open3D's OpenMP loops stall on small machines.
"""
import json
import statistics
import sys
import time

import numpy as np
import open3d as o3d


def median_ms(samples):
    return statistics.median(samples) * 1000.0 if samples else None


def run_legacy(m, frames):
    intr = o3d.camera.PinholeCameraIntrinsic(m["width"], m["height"], m["fx"], m["fy"], m["cx"], m["cy"])
    vol = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=m["voxel_size_m"], sdf_trunc=m["trunc_m"],
        color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
    times = []
    for depth, color, T_W_C in frames:
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            color, depth, depth_scale=m["depth_scale"], depth_trunc=m["max_depth_m"],
            convert_rgb_to_intensity=False)
        t0 = time.perf_counter()
        vol.integrate(rgbd, intr, np.linalg.inv(T_W_C))
        times.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    mesh = vol.extract_triangle_mesh()
    mesh_s = time.perf_counter() - t0
    return times, mesh_s, len(mesh.triangles)


def run_vbg(m, frames):
    dev = o3d.core.Device("CPU:0")
    K = o3d.core.Tensor([[m["fx"], 0, m["cx"]], [0, m["fy"], m["cy"]], [0, 0, 1]], o3d.core.float64)
    vbg = o3d.t.geometry.VoxelBlockGrid(
        attr_names=("tsdf", "weight", "color"),
        attr_dtypes=(o3d.core.float32, o3d.core.float32, o3d.core.float32),
        attr_channels=((1), (1), (3)), voxel_size=m["voxel_size_m"], block_resolution=8,
        block_count=m.get("vbg_block_count", 200000), device=dev)
    times = []
    for depth, color, T_W_C in frames:
        extrinsic = o3d.core.Tensor(np.linalg.inv(T_W_C), o3d.core.float64)
        t0 = time.perf_counter()
        coords = vbg.compute_unique_block_coordinates(
            depth, K, extrinsic, m["depth_scale"], m["max_depth_m"],
            trunc_voxel_multiplier=m["trunc_m"] / m["voxel_size_m"])
        vbg.integrate(coords, depth, color, K, extrinsic, m["depth_scale"], m["max_depth_m"],
                      trunc_voxel_multiplier=m["trunc_m"] / m["voxel_size_m"])
        times.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    mesh = vbg.extract_triangle_mesh()
    mesh_s = time.perf_counter() - t0
    return times, mesh_s, len(mesh.triangle.indices) if "indices" in mesh.triangle else 0


def main():
    manifest = json.load(open(sys.argv[1]))
    paths = manifest.get("paths", ["legacy", "vbg"])
    legacy_frames, vbg_frames = [], []
    for f in manifest["frames"]:
        if not f["color"]:
            sys.exit("open3d_fusion.py: the frame list has frames without colour: " + f["depth"])
        T = np.array(f["T_W_C"], dtype=np.float64).reshape(4, 4)
        if "legacy" in paths:
            legacy_frames.append((o3d.io.read_image(f["depth"]), o3d.io.read_image(f["color"]), T))
        if "vbg" in paths:
            vbg_frames.append((o3d.t.io.read_image(f["depth"]), o3d.t.io.read_image(f["color"]), T))
    out = {"open3d_version": o3d.__version__, "frames": len(manifest["frames"])}
    if "legacy" in paths:
        t, mesh_s, tris = run_legacy(manifest, legacy_frames)
        out.update(open3d_legacy_ms_median=median_ms(t), open3d_legacy_mesh_ms=mesh_s * 1000.0,
                   open3d_legacy_mesh_triangles=tris)
    if "vbg" in paths:
        t, mesh_s, tris = run_vbg(manifest, vbg_frames)
        out.update(open3d_vbg_ms_median=median_ms(t), open3d_vbg_mesh_ms=mesh_s * 1000.0,
                   open3d_vbg_mesh_triangles=tris)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
