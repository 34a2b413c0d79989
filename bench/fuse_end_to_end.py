#!/usr/bin/python3
"""The whole `fuse` job, end to end, side by side in one run: voxplan with frames decoded ahead
(--prefetch, the default), the same binary with --prefetch 0 (decode, then fuse, one frame after
the other), optionally an older voxplan binary (--before, e.g. a build from before a change),
and Open3D's Python pipelines on the same frames (bench/open3d_fusion.py --end-to-end).

Each arm runs as its own process doing the whole job: decode every frame, integrate it with
colour, extract the mesh, write it as binary PLY. The arms run in turn, the order rotated from
one repeat to the next (repeat r starts with arm r mod the number of arms), so each repeat is
one paired set measured under the same load. Per run: the process's wall time, its CPU time
(user + sys, from getrusage of the children), and the job's own figures (voxplan's stats line:
loop_s, fps; Open3D's: job_s, loop_s, fps, import_s). Per arm: medians over the repeats with
the min-max range (for 5 repeats, a 94 % distribution-free interval for the median); per pair
of arms: the median of the per-repeat ratios with a seeded 95 % bootstrap interval.

  bench/fuse_end_to_end.py ../shared/data/rgbd/7scenes_redkitchen --frames 200 \\
      --before /tmp/voxplan-before --repeat 5 --json 7s.json

Prints a table on stderr and one JSON object as the last stdout line. Run it under the build
lock (flock /tmp/voxplan-build.lock ...) so no build shares the machine; the load average at
each run is recorded (other tenants still run).
"""
import argparse
import json
import os
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def log(message):
    print("fuse_end_to_end.py: " + message, file=sys.stderr, flush=True)


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(argv, env=None):
    """Runs argv; returns (wall s, cpu s, last stdout line as JSON)."""
    cpu0, t0 = cpu_children(), time.perf_counter()
    p = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, text=True)
    wall, cpu = time.perf_counter() - t0, cpu_children() - cpu0
    if p.returncode != 0:
        sys.exit("fuse_end_to_end.py: %s failed (exit %d):\n%s"
                 % (" ".join(argv), p.returncode, p.stderr[-2000:]))
    lines = [l for l in p.stdout.splitlines() if l.strip()]
    return wall, cpu, json.loads(lines[-1])


def quantile(v, q):
    v = sorted(v)
    pos = q * (len(v) - 1)
    lo = int(pos)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (pos - lo) * (v[hi] - v[lo])


def bootstrap_median(values, seed=1, rounds=2000):
    rng = random.Random(seed)
    meds = sorted(statistics.median(rng.choices(values, k=len(values))) for _ in range(rounds))
    return [quantile(meds, 0.025), quantile(meds, 0.975)]


def summary(values, digits=3):
    return {"median": round(statistics.median(values), digits),
            "min": round(min(values), digits), "max": round(max(values), digits),
            "all": [round(v, digits) for v in values]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dataset")
    ap.add_argument("--voxplan", default=os.path.join(ROOT, "build/apps/voxplan/voxplan"))
    ap.add_argument("--before", default="", help="another voxplan binary to run as it is")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--voxel-size", default="0.01")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--prefetch", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--open3d", default="legacy,vbg",
                    help="Open3D paths to run, comma-separated ('' for none)")
    # Measured here with other tenants on both cores: ACTIVE (what `voxplan bench` sets, for an
    # idle machine) made Open3D's legacy loop 6x slower at 2 threads, PASSIVE none.
    ap.add_argument("--omp-wait-policy", default="PASSIVE", choices=["PASSIVE", "ACTIVE"],
                    help="OMP_WAIT_POLICY for the Open3D runs")
    ap.add_argument("--json", default="")
    args = ap.parse_args()
    if args.repeat < 1:
        sys.exit("fuse_end_to_end.py: --repeat must be at least 1")

    tmp = tempfile.mkdtemp(prefix="voxplan-e2e-")
    common = ["fuse", args.dataset, "--frames", str(args.frames), "--voxel-size",
              args.voxel_size, "--threads", str(args.threads)]
    # The frames voxplan integrates, for Open3D: the `fuse --frame-list` layout, plus a VBG
    # capacity from voxplan's block count (as `voxplan bench` sizes it).
    list_path = os.path.join(tmp, "frames.json")
    _, _, first = run([args.voxplan] + common + ["--frame-list", list_path])
    with open(list_path) as f:
        frame_list = json.load(f)
    frame_list["vbg_block_count"] = max(1024, first["blocks"] * 5 // 4)
    with open(list_path, "w") as f:
        json.dump(frame_list, f)

    arms = []  # (name, argv, env, kind)
    if args.before:
        arms.append(("before", [args.before] + common, None, "voxplan"))
    arms.append(("prefetch0", [args.voxplan] + common + ["--prefetch", "0"], None, "voxplan"))
    arms.append(("prefetch%d" % args.prefetch,
                 [args.voxplan] + common + ["--prefetch", str(args.prefetch)], None, "voxplan"))
    o3d_env = dict(os.environ, OMP_NUM_THREADS=str(args.threads),
                   OMP_WAIT_POLICY=args.omp_wait_policy)
    for path in [p for p in args.open3d.split(",") if p]:
        arms.append(("open3d_" + path,
                     ["/usr/bin/python3", os.path.join(HERE, "open3d_fusion.py"), list_path,
                      "--path", path, "--end-to-end", os.path.join(tmp, "o3d_%s.ply" % path)],
                     o3d_env, "open3d"))
    results = {name: [] for name, _, _, _ in arms}
    for r in range(args.repeat):
        order = arms[r % len(arms):] + arms[:r % len(arms)]
        for name, argv, env, kind in order:
            if kind == "voxplan":
                argv = argv + ["--mesh", os.path.join(tmp, name + ".ply")]
            load = os.getloadavg()[0]
            wall, cpu, j = run(argv, env)
            if kind == "voxplan":
                rec = {"wall_s": wall, "cpu_s": cpu, "job_s": wall, "loop_s": j["loop_s"],
                       "fps": j["fps"], "frames": j["frames"], "triangles": j["mesh_triangles"]}
            else:
                rec = {"wall_s": wall, "cpu_s": cpu, "job_s": j["job_s"], "loop_s": j["loop_s"],
                       "fps": j["fps"], "frames": j["frames"], "triangles": j["triangles"],
                       "import_s": j["import_s"]}
            rec["load1"] = load
            results[name].append(rec)
            log("repeat %d/%d %-12s wall %.2f s, cpu %.2f s, loop %.2f s, %.1f fps (load %.2f)"
                % (r + 1, args.repeat, name, wall, cpu, rec["loop_s"], rec["fps"], load))

    out = {"command": "fuse_end_to_end", "dataset": args.dataset, "frames": first["frames"],
           "frames_selected": args.frames, "voxel_size_m": float(args.voxel_size),
           "threads": args.threads, "prefetch": args.prefetch, "repeat": args.repeat,
           "nproc": os.cpu_count(), "omp_wait_policy": args.omp_wait_policy, "arms": {},
           "ratios": {}}
    for name, _, _, kind in arms:
        recs = results[name]
        out["arms"][name] = {k: summary([x[k] for x in recs])
                             for k in ("wall_s", "cpu_s", "job_s", "loop_s", "fps", "load1")}
        if kind == "open3d":
            out["arms"][name]["import_s"] = summary([x["import_s"] for x in recs])
        out["arms"][name]["triangles"] = recs[0]["triangles"]
        out["arms"][name]["frames"] = recs[0]["frames"]

    def ratio(key, num, den):  # per repeat num / den
        v = [a[key] / b[key] for a, b in zip(results[num], results[den])]
        return {"median": round(statistics.median(v), 3),
                "bootstrap95": [round(x, 3) for x in bootstrap_median(v)],
                "min": round(min(v), 3), "max": round(max(v), 3)}

    new = "prefetch%d" % args.prefetch
    base = "before" if args.before else "prefetch0"
    # > 1: the new arm is faster.
    out["ratios"]["fps_%s_over_%s" % (new, base)] = ratio("fps", new, base)
    out["ratios"]["wall_%s_over_%s" % (base, new)] = ratio("wall_s", base, new)
    if args.before:
        out["ratios"]["fps_prefetch0_over_before"] = ratio("fps", "prefetch0", "before")
        out["ratios"]["wall_before_over_prefetch0"] = ratio("wall_s", "before", "prefetch0")
    for name, _, _, kind in arms:
        if kind == "open3d":
            out["ratios"]["wall_%s_over_%s" % (name, new)] = ratio("wall_s", name, new)
            out["ratios"]["job_%s_over_%s" % (name, new)] = ratio("job_s", name, new)
            if args.before:
                out["ratios"]["wall_%s_over_before" % name] = ratio("wall_s", name, "before")

    print("%-12s %8s %8s %8s %8s %6s" % ("arm", "wall s", "cpu s", "job s", "fps", "load"),
          file=sys.stderr)
    for name, a in out["arms"].items():
        print("%-12s %8.2f %8.2f %8.2f %8.1f %6.2f" % (
            name, a["wall_s"]["median"], a["cpu_s"]["median"], a["job_s"]["median"],
            a["fps"]["median"], a["load1"]["median"]), file=sys.stderr)
    for name, rr in out["ratios"].items():
        print("%-40s %6.3f  [%.3f, %.3f]" % (name, rr["median"], *rr["bootstrap95"]),
              file=sys.stderr)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
    for f in os.listdir(tmp):
        os.remove(os.path.join(tmp, f))
    os.rmdir(tmp)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
