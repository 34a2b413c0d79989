#!/usr/bin/python3
"""Open3D reference timings for voxplan's fusion benchmarks (`voxplan bench ... --vs-open3d`).

Reads the frame list that `voxplan fuse --frame-list F.json` and `voxplan bench` write
(intrinsics, depth scale, parameters, and the integrated frames: depth/colour paths and
row-major 4x4 camera-to-world poses) and runs one of Open3D's TSDF pipelines on identical
frames and parameters:

  --path legacy   o3d.pipelines.integration.ScalableTSDFVolume (RGB8 colour)
  --path vbg      o3d.t.geometry.VoxelBlockGrid on the CPU (tsdf, weight: float; colour: 3 floats)

Frames are streamed as voxplan streams them: each is decoded (timed as load, outside the
integration timing), then integrated (timed). Every repeat starts from a fresh volume; the
reported integration time is the median over repeats of each repeat's per-frame median. After
each repeat the mesh is extracted (timed; median over repeats). For VBG, the final volume is
also ray cast (depth, normal, colour) at the poses of --raycast-poses (indexes into the list's
frames), each --raycast-rounds times, over the blocks in that frame's view frustum; the
legacy volume has no ray caster.

With --end-to-end MESH.ply the whole job is timed once instead, as `voxplan fuse --mesh` does
it: every frame decoded and integrated (with colour), the mesh extracted and written (binary
PLY). The JSON then gives job_s (from the first decode to the written mesh), its parts, and
import_s (Python, NumPy and Open3D loading before it); bench/fuse_end_to_end.py runs it.

Prints progress on stderr and one JSON object as the last stdout line. Run one path per
process so each peak RSS (VmHWM) is its own. Set OMP_WAIT_POLICY=ACTIVE and
OMP_NUM_THREADS (voxplan bench does), or Open3D's OpenMP loops stall on small machines.
"""
import time

_PROCESS_START = time.perf_counter()  # before the imports, which --end-to-end reports

import argparse
import json
import math
import os
import resource
import statistics
import sys

SETUP_HINT = "install it with scripts/setup-deps --bench (Debian's python3-open3d)"

try:
    import numpy as np
    import open3d as o3d
except ImportError as e:  # the caller shows this line as the reason
    sys.exit("open3d_fusion.py: cannot import %s; %s" % (e.name, SETUP_HINT))


def quantile(values, q):
    """Linear interpolation between closest ranks (as voxplan's Summarize)."""
    v = sorted(values)
    if not v:
        return None
    pos = q * (len(v) - 1)
    lo = int(math.floor(pos))
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (pos - lo) * (v[hi] - v[lo])


def rounded(x, digits=3):
    return None if x is None else round(x, digits)


def peak_rss_mb():
    # VmHWM, not ru_maxrss: Linux carries the spawning process's peak into ru_maxrss across
    # exec, so a large parent (voxplan) would show as this process's peak.
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0  # kB
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def log(message):
    print("open3d_fusion.py: " + message, file=sys.stderr, flush=True)


class Timings:
    """Per-frame samples of one repeat -> per-repeat medians and p90s."""

    def __init__(self):
        self.repeat_medians, self.repeat_p90s, self.load_ms = [], [], []

    def add_repeat(self, integrate_ms, load_ms):
        self.repeat_medians.append(quantile(integrate_ms, 0.5))
        self.repeat_p90s.append(quantile(integrate_ms, 0.9))
        self.load_ms.extend(load_ms)

    def keys(self, prefix):
        return {
            prefix + "_ms_median": rounded(statistics.median(self.repeat_medians)),
            prefix + "_ms_p90": rounded(statistics.median(self.repeat_p90s)),
            prefix + "_repeat_medians_ms": [rounded(x) for x in self.repeat_medians],
            prefix + "_load_ms_median": rounded(quantile(self.load_ms, 0.5)),
        }


def run_legacy(m, args):
    intr = o3d.camera.PinholeCameraIntrinsic(m["width"], m["height"], m["fx"], m["fy"], m["cx"],
                                             m["cy"])
    timings, mesh_ms = Timings(), []
    triangles = 0
    for r in range(args.repeat):
        vol = o3d.pipelines.integration.ScalableTSDFVolume(
            voxel_length=m["voxel_size_m"], sdf_trunc=m["trunc_m"],
            color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
        integrate_ms, load_ms = [], []
        for f in m["frames"]:
            t0 = time.perf_counter()
            depth = o3d.io.read_image(f["depth"])
            color = o3d.io.read_image(f["color"])
            # Scaling depth to metres and cutting at max depth is decoding work, as in
            # voxplan's Dataset::Load.
            rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
                color, depth, depth_scale=m["depth_scale"], depth_trunc=m["max_depth_m"],
                convert_rgb_to_intensity=False)
            extrinsic = np.linalg.inv(np.array(f["T_W_C"], dtype=np.float64).reshape(4, 4))
            t1 = time.perf_counter()
            vol.integrate(rgbd, intr, extrinsic)
            t2 = time.perf_counter()
            load_ms.append((t1 - t0) * 1000.0)
            integrate_ms.append((t2 - t1) * 1000.0)
        timings.add_repeat(integrate_ms, load_ms)
        t0 = time.perf_counter()
        mesh = vol.extract_triangle_mesh()
        mesh_ms.append((time.perf_counter() - t0) * 1000.0)
        triangles = len(mesh.triangles)
        del mesh, vol
        log("legacy repeat %d/%d: integrate median %.2f ms, mesh %.1f ms"
            % (r + 1, args.repeat, timings.repeat_medians[-1], mesh_ms[-1]))
    out = timings.keys("open3d_legacy")
    out.update(open3d_legacy_mesh_ms=rounded(statistics.median(mesh_ms)),
               open3d_legacy_mesh_triangles=triangles,
               open3d_legacy_raycast_ms_median=None,  # ScalableTSDFVolume has no ray caster
               # Voxels live in shared_ptr'd 16^3 units of C++ TSDFVoxel objects that Python
               # cannot see; nothing here measures them.
               open3d_legacy_bytes_per_voxel="n/a")
    return out


def run_vbg(m, args):
    dev = o3d.core.Device("CPU:0")
    K = o3d.core.Tensor([[m["fx"], 0, m["cx"]], [0, m["fy"], m["cy"]], [0, 0, 1]],
                        o3d.core.float64)
    trunc_mult = m["trunc_m"] / m["voxel_size_m"]
    # VBG allocates (and touches) all block_count blocks up front, so the capacity decides its
    # RSS: size it from voxplan's block count (written into the list) rather than a guess.
    block_count = args.block_count or m.get("vbg_block_count", 200000)
    timings, mesh_ms = Timings(), []
    triangles = 0
    vbg = None
    for r in range(args.repeat):
        vbg = None  # free the previous repeat's buffers before allocating the next
        vbg = o3d.t.geometry.VoxelBlockGrid(
            attr_names=("tsdf", "weight", "color"),
            attr_dtypes=(o3d.core.float32, o3d.core.float32, o3d.core.float32),
            attr_channels=((1), (1), (3)), voxel_size=m["voxel_size_m"], block_resolution=8,
            block_count=block_count, device=dev)
        integrate_ms, load_ms = [], []
        for f in m["frames"]:
            t0 = time.perf_counter()
            depth = o3d.t.io.read_image(f["depth"])
            color = o3d.t.io.read_image(f["color"])
            extrinsic = o3d.core.Tensor(
                np.linalg.inv(np.array(f["T_W_C"], dtype=np.float64).reshape(4, 4)),
                o3d.core.float64)
            t1 = time.perf_counter()
            coords = vbg.compute_unique_block_coordinates(
                depth, K, extrinsic, m["depth_scale"], m["max_depth_m"],
                trunc_voxel_multiplier=trunc_mult)
            vbg.integrate(coords, depth, color, K, extrinsic, m["depth_scale"], m["max_depth_m"],
                          trunc_voxel_multiplier=trunc_mult)
            t2 = time.perf_counter()
            load_ms.append((t1 - t0) * 1000.0)
            integrate_ms.append((t2 - t1) * 1000.0)
        timings.add_repeat(integrate_ms, load_ms)
        t0 = time.perf_counter()
        # 0.5 as voxplan's mesh min_weight (the default 3.0 would drop thinly seen surface).
        mesh = vbg.extract_triangle_mesh(weight_threshold=0.5)
        mesh_ms.append((time.perf_counter() - t0) * 1000.0)
        triangles = len(mesh.triangle.indices) if "indices" in mesh.triangle else 0
        del mesh
        log("vbg repeat %d/%d: integrate median %.2f ms, mesh %.1f ms"
            % (r + 1, args.repeat, timings.repeat_medians[-1], mesh_ms[-1]))

    # Ray cast over the blocks in the view frustum of the frame's own depth (computed outside
    # the timing), as Open3D's examples do: in 0.16, ray_cast over every key of the hash map
    # never returned on ICL-NUIM (a spin inside the CPU kernel once the range map is regrown).
    views = []
    for i in args.raycast_poses:
        f = m["frames"][i]
        extrinsic = o3d.core.Tensor(
            np.linalg.inv(np.array(f["T_W_C"], dtype=np.float64).reshape(4, 4)), o3d.core.float64)
        coords = vbg.compute_unique_block_coordinates(
            o3d.t.io.read_image(f["depth"]), K, extrinsic, m["depth_scale"], m["max_depth_m"],
            trunc_voxel_multiplier=trunc_mult)
        views.append((coords, extrinsic))
    raycast_ms, hits = [], []
    for round_index in range(args.raycast_rounds):
        for coords, extrinsic in views:
            t0 = time.perf_counter()
            result = vbg.ray_cast(block_coords=coords, intrinsic=K, extrinsic=extrinsic,
                                  width=m["width"], height=m["height"],
                                  render_attributes=["depth", "normal", "color"],
                                  depth_scale=m["depth_scale"], depth_min=m["min_depth_m"],
                                  depth_max=m["max_depth_m"], weight_threshold=1,
                                  trunc_voxel_multiplier=trunc_mult, range_map_down_factor=8)
            raycast_ms.append((time.perf_counter() - t0) * 1000.0)
            if round_index == 0:
                hits.append(float((result["depth"].numpy() > 0).mean()))

    hashmap = vbg.hashmap()
    # Attribute bytes per voxel (4 + 4 + 12) plus the hash map's share per block: the int32
    # key and the int32 buffer index, spread over the block's 512 voxels.
    attr_bytes = sum(t.dtype.byte_size() * t.shape[-1] for t in hashmap.value_tensors())
    key_bytes = hashmap.key_tensor().dtype.byte_size() * 3
    out = timings.keys("open3d_vbg")
    out.update(open3d_vbg_mesh_ms=rounded(statistics.median(mesh_ms)),
               open3d_vbg_mesh_triangles=triangles,
               open3d_vbg_raycast_ms_median=rounded(quantile(raycast_ms, 0.5)),
               open3d_vbg_raycast_views=len(args.raycast_poses),
               open3d_vbg_raycast_hit_fraction=rounded(statistics.mean(hits), 4),
               open3d_vbg_blocks=hashmap.size(),
               open3d_vbg_block_capacity=hashmap.capacity(),
               open3d_vbg_reserved_mb=rounded(hashmap.capacity() * 512 * attr_bytes / 2**20, 1),
               open3d_vbg_bytes_per_voxel=rounded(attr_bytes + (key_bytes + 4) / 512.0, 3))
    return out


def run_end_to_end(m, args):
    """One whole job: decode, integrate with colour, extract the mesh, write it."""
    import_s = time.perf_counter() - _PROCESS_START
    frames = m["frames"]
    t0 = time.perf_counter()
    if args.path == "legacy":
        intr = o3d.camera.PinholeCameraIntrinsic(m["width"], m["height"], m["fx"], m["fy"],
                                                 m["cx"], m["cy"])
        vol = o3d.pipelines.integration.ScalableTSDFVolume(
            voxel_length=m["voxel_size_m"], sdf_trunc=m["trunc_m"],
            color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
        for f in frames:
            rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
                o3d.io.read_image(f["color"]), o3d.io.read_image(f["depth"]),
                depth_scale=m["depth_scale"], depth_trunc=m["max_depth_m"],
                convert_rgb_to_intensity=False)
            vol.integrate(rgbd, intr,
                          np.linalg.inv(np.array(f["T_W_C"], dtype=np.float64).reshape(4, 4)))
        t1 = time.perf_counter()
        mesh = vol.extract_triangle_mesh()
        triangles = len(mesh.triangles)
        t2 = time.perf_counter()
        ok = o3d.io.write_triangle_mesh(args.end_to_end, mesh, write_ascii=False)
    else:
        dev = o3d.core.Device("CPU:0")
        K = o3d.core.Tensor([[m["fx"], 0, m["cx"]], [0, m["fy"], m["cy"]], [0, 0, 1]],
                            o3d.core.float64)
        trunc_mult = m["trunc_m"] / m["voxel_size_m"]
        vbg = o3d.t.geometry.VoxelBlockGrid(
            attr_names=("tsdf", "weight", "color"),
            attr_dtypes=(o3d.core.float32, o3d.core.float32, o3d.core.float32),
            attr_channels=((1), (1), (3)), voxel_size=m["voxel_size_m"], block_resolution=8,
            block_count=args.block_count or m.get("vbg_block_count", 200000), device=dev)
        for f in frames:
            depth = o3d.t.io.read_image(f["depth"])
            color = o3d.t.io.read_image(f["color"])
            extrinsic = o3d.core.Tensor(
                np.linalg.inv(np.array(f["T_W_C"], dtype=np.float64).reshape(4, 4)),
                o3d.core.float64)
            coords = vbg.compute_unique_block_coordinates(
                depth, K, extrinsic, m["depth_scale"], m["max_depth_m"],
                trunc_voxel_multiplier=trunc_mult)
            vbg.integrate(coords, depth, color, K, extrinsic, m["depth_scale"], m["max_depth_m"],
                          trunc_voxel_multiplier=trunc_mult)
        t1 = time.perf_counter()
        mesh = vbg.extract_triangle_mesh(weight_threshold=0.5)
        triangles = len(mesh.triangle.indices) if "indices" in mesh.triangle else 0
        t2 = time.perf_counter()
        ok = o3d.t.io.write_triangle_mesh(args.end_to_end, mesh, write_ascii=False)
    t3 = time.perf_counter()
    if not ok:
        sys.exit("open3d_fusion.py: cannot write " + args.end_to_end)
    log("%s end to end: %d frames, loop %.2f s, mesh %.2f s, write %.2f s (import %.2f s)"
        % (args.path, len(frames), t1 - t0, t2 - t1, t3 - t2, import_s))
    return {"end_to_end": True, "import_s": rounded(import_s), "job_s": rounded(t3 - t0),
            "loop_s": rounded(t1 - t0), "mesh_s": rounded(t2 - t1), "write_s": rounded(t3 - t2),
            "fps": rounded(len(frames) / (t1 - t0), 2), "triangles": triangles,
            "mesh": args.end_to_end}


def parse_indexes(text):
    try:
        return [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("not a comma-separated list of indexes: " + text)


def positive_int(text):
    v = int(text)
    if v < 1:
        raise argparse.ArgumentTypeError("must be at least 1: " + text)
    return v


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("frame_list", help="frame list JSON (voxplan fuse --frame-list)")
    parser.add_argument("--path", choices=["legacy", "vbg"], required=True)
    parser.add_argument("--repeat", type=positive_int, default=3)
    parser.add_argument("--raycast-poses", type=parse_indexes, default=[],
                        help="comma-separated indexes into the list's frames (VBG only)")
    parser.add_argument("--raycast-rounds", type=positive_int, default=3)
    parser.add_argument("--block-count", type=positive_int, default=0,
                        help="VBG capacity in blocks (default: the list's vbg_block_count)")
    parser.add_argument("--end-to-end", metavar="MESH_PLY", default="",
                        help="time one whole job instead: decode, integrate, mesh, write MESH_PLY")
    args = parser.parse_args()

    with open(args.frame_list) as f:
        m = json.load(f)
    frames = m["frames"]
    if not frames:
        sys.exit("open3d_fusion.py: the frame list has no frames: " + args.frame_list)
    for f in frames:
        if not f["color"]:
            sys.exit("open3d_fusion.py: the frame list has frames without colour: " + f["depth"])
    if not args.raycast_poses:
        args.raycast_poses = [0]
    bad = [i for i in args.raycast_poses if not 0 <= i < len(frames)]
    if bad:
        sys.exit("open3d_fusion.py: --raycast-poses out of range (%d frames): %s"
                 % (len(frames), bad))

    # What importing Open3D and NumPy costs before any volume exists, to read the peak against.
    out = {"open3d_version": o3d.__version__, "path": args.path, "frames": len(frames),
           "repeat": args.repeat, "omp_num_threads": os.environ.get("OMP_NUM_THREADS"),
           "open3d_baseline_rss_mb": rounded(peak_rss_mb(), 1)}
    log("%s: %d frames, voxel %g m, %d repeats, OMP_NUM_THREADS=%s"
        % (args.path, len(frames), m["voxel_size_m"], args.repeat, out["omp_num_threads"]))
    if args.end_to_end:
        out.update(run_end_to_end(m, args))
    else:
        out.update(run_legacy(m, args) if args.path == "legacy" else run_vbg(m, args))
    out["open3d_%s_peak_rss_mb" % args.path] = rounded(peak_rss_mb(), 1)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
