#!/usr/bin/python3
"""Sharded fusion under mpirun: what each rank holds and does, and a model of a real cluster.

For each voxel size and rank count, `mpirun -n N voxplan fuse DATASET --frames F --threads T`
(N = 1 also without mpirun, the one-process reference; N > 1 with --band-walk split and whole)
and its stats:

  rank_peak_rss_mb   peak resident memory of every rank (the aim: about 1/N of one process's map)
  rank_blocks        blocks each rank owns (balance of the chunk hash)
  broadcast          bytes and time per frame rank 0 broadcasts (decoded depth + colour)
  collect_ms         per frame, walking the truncation band to find one's blocks: with
                     --band-walk whole every rank repeats it all (the repeated share); split (the
                     default), each walks 1/N and the ranks exchange what they found
  exchange_ms        per frame, that exchange (an all-to-all of block indices)
  update_ms          per frame, updating one's own blocks: split over the ranks (the split share)

On a machine with fewer cores than N x T the wall times say nothing about scaling (the ranks
share the cores); the model says what a cluster would see from the measured shares:

  t(N) = decode / prefetch overlap + broadcast(N) + walk(N) + update(1) * imbalance(N) / N
  walk(N) = collect(1) (whole) or collect(1) / N + exchange (split)

with broadcast(N) = bytes / bandwidth * ceil(log2 N) (a binomial tree over --bandwidth-gbps) and
imbalance(N) = max / mean of the blocks each of N ranks would own of the whole map (the owner
hash applied to the one-process map; a single frame's share is less even than the map's); decode runs ahead on rank 0 and is hidden
while it is shorter than the rest. One JSON object on the last stdout line (and --json FILE).

    /usr/bin/python3 bench/mpi_scaling.py ../shared/data/rgbd/7scenes_redkitchen --frames 100 \\
        --voxel-sizes 0.005,0.002 --ranks 1,2,4 --json mpi_scaling.json
"""

from __future__ import annotations

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile


def owner(bx: int, by: int, bz: int, ranks: int) -> int:
    """core/shard.h's BlockOwner: splitmix64 of the 8^3-block chunk, mod ranks."""
    m = (1 << 64) - 1
    c = lambda v: (v >> 3) & 0x1fffff  # arithmetic shift, as int32 >> 3 in C++
    k = c(bx) | (c(by) << 21) | (c(bz) << 42)
    k ^= k >> 30
    k = (k * 0xbf58476d1ce4e5b9) & m
    k ^= k >> 27
    k = (k * 0x94d049bb133111eb) & m
    k ^= k >> 31
    return k % ranks


def map_blocks(path: str) -> list:
    """The block indices of a plain .vpmap (io/map_io.h: header, then index + block each)."""
    with open(path, "rb") as f:
        data = f.read()
    version = struct.unpack_from("<I", data, 8)[0]
    header = 28 if version == 1 else None
    if header is None:  # later versions: find the count after the fixed fields
        header = len(data) - 8 - (len(data) - 8 - 28) // (12 + 7 * 512) * (12 + 7 * 512)
    count = (len(data) - 8 - header) // (12 + 7 * 512)
    return [struct.unpack_from("<iii", data, header + i * (12 + 7 * 512)) for i in range(count)]


def imbalance(blocks: list, ranks: int) -> float:
    counts = [0] * ranks
    for b in blocks:
        counts[owner(*b, ranks)] += 1
    return max(counts) / (sum(counts) / ranks) if blocks else 1.0


def run_fuse(voxplan: str, dataset: str, frames: int, voxel: float, ranks: int, threads: int,
             mpirun: bool, out: str, walk: str = "split") -> dict:
    stats = os.path.join(out, f"v{voxel}_n{ranks}_{walk}_{'mpi' if mpirun else 'one'}.json")
    cmd = [voxplan, "fuse", dataset, "--frames", str(frames), "--voxel-size", str(voxel),
           "--trunc", str(4 * voxel), "--threads", str(threads), "--stats", stats,
           "--band-walk", walk]
    if not mpirun:
        cmd += ["--map", os.path.join(out, f"v{voxel}.vpmap")]
    if mpirun:
        cmd = ["mpirun", "--bind-to", "none", "--oversubscribe", "-n", str(ranks)] + cmd
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    print("mpi_scaling: " + " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    with open(stats) as f:
        return json.load(f)


def exchange_ms(rows: list) -> float:
    """The split walk's exchange as a cluster would see it: measured with no more ranks than this
    machine has cores (more are time-sliced, and the all-to-all then waits for descheduled ranks);
    the largest such, else the largest of all."""
    split = [r for r in rows if r["band_walk"] == "split" and r["ranks"] > 1]
    fit = [r for r in split if r["ranks"] <= (os.cpu_count() or 1)]
    return max((r.get("exchange_ms_median") or 0.0) for r in (fit or split)) if split else 0.0


def model(row1: dict, mb_per_frame: float, blocks: list, ranks: int,
          bandwidth_gbps: float, split_walk: bool, exchange_ms: float) -> dict:
    """Per-frame time on a cluster of `ranks` nodes from the one-rank shares. With the band
    walk split, each rank walks 1/N of it and the exchange (exchange_ms) is added; else every
    rank walks it all."""
    collect = row1["collect_ms_median"] / (ranks if split_walk else 1)
    if split_walk and ranks > 1:
        collect += exchange_ms
    update1 = row1["update_ms_median"]
    decode = row1["load_ms_median"]
    imb = imbalance(blocks, ranks)
    # MiB -> megabits, over Gbit/s -> ms, once per level of the broadcast tree.
    bcast = (mb_per_frame * 8 * 1.048576 / bandwidth_gbps) * math.ceil(math.log2(ranks)) \
        if ranks > 1 else 0.0
    work = bcast + collect + update1 * imb / ranks
    t = max(decode, work)  # decoding runs ahead on rank 0
    t1 = max(decode, row1["collect_ms_median"] + update1)
    return {"ranks": ranks, "imbalance": round(imb, 3), "broadcast_ms": round(bcast, 3),
            "frame_ms": round(t, 3), "speedup": round(t1 / t, 2),
            "bound": "decode" if decode >= work else "fusion"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dataset")
    ap.add_argument("--voxplan", default="build/apps/voxplan/voxplan")
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--voxel-sizes", default="0.005,0.002")
    ap.add_argument("--ranks", default="1,2,4")
    ap.add_argument("--threads", type=int, default=1, help="per rank")
    ap.add_argument("--bandwidth-gbps", type=float, default=10.0,
                    help="the model's network (10: 10 GbE; 100: InfiniBand EDR)")
    ap.add_argument("--model-ranks", default="1,2,4,8,16,32")
    ap.add_argument("--json")
    args = ap.parse_args()
    rank_counts = [int(r) for r in args.ranks.split(",")]
    out = {"dataset": args.dataset, "frames": args.frames, "threads_per_rank": args.threads,
           "cores_here": os.cpu_count(), "bandwidth_gbps": args.bandwidth_gbps, "sizes": []}
    with tempfile.TemporaryDirectory() as tmp:
        for voxel in [float(v) for v in args.voxel_sizes.split(",")]:
            one = run_fuse(args.voxplan, args.dataset, args.frames, voxel, 1, args.threads,
                           False, tmp)
            blocks = map_blocks(os.path.join(tmp, f"v{voxel}.vpmap"))
            rows = []
            for n, walk in [(n, w) for n in rank_counts for w in (["split", "whole"] if n > 1
                                                                   else ["split"])]:
                s = run_fuse(args.voxplan, args.dataset, args.frames, voxel, n, args.threads,
                             True, tmp, walk)
                rows.append({k: s.get(k) for k in [
                    "ranks", "blocks", "map_mb", "rank_blocks", "rank_map_mb", "rank_peak_rss_mb",
                    "broadcast_mb_per_frame", "broadcast_ms_median", "collect_ms_median",
                    "update_ms_median", "exchange_ms_median", "integrate_ms_median",
                    "load_ms_median", "loop_s", "fps"]})
                rows[-1]["band_walk"] = walk if n > 1 else "none"
                # One rank runs the one-process code path: its figures are the process's own.
                rows[-1]["ranks"] = n
                if n == 1:
                    rows[-1].update(rank_blocks=[s["blocks"]], rank_map_mb=[s["map_mb"]],
                                    rank_peak_rss_mb=[s["peak_rss_mb"]])
            base = rows[0]
            share = base["collect_ms_median"] / max(
                base["collect_ms_median"] + base["update_ms_median"], 1e-9)
            entry = {
                "voxel_size_m": voxel,
                "one_process": {k: one.get(k) for k in ["blocks", "map_mb", "peak_rss_mb",
                                                        "integrate_ms_median", "load_ms_median",
                                                        "loop_s", "fps"]},
                "runs": rows,
                "repeated_share": round(share, 3),
                "model": {walk: [model(base, max(r["broadcast_mb_per_frame"] or 0.0 for r in rows),
                                       blocks, m, args.bandwidth_gbps, walk == "split",
                                       exchange_ms(rows))
                                 for m in [int(x) for x in args.model_ranks.split(",")]]
                          for walk in ["whole", "split"]},
            }
            out["sizes"].append(entry)
            print(f"voxel {voxel} m: one process {one['peak_rss_mb']} MiB peak, "
                  f"{one['map_mb']} MiB map; repeated share {share:.2f}", file=sys.stderr)
            for r in rows:
                print(f"  {r['ranks']} ranks ({r['band_walk']} walk): peak RSS per rank {r['rank_peak_rss_mb']} MiB, "
                      f"map per rank {r['rank_map_mb']} MiB, broadcast "
                      f"{r['broadcast_mb_per_frame']} MiB / {r['broadcast_ms_median']} ms, collect "
                      f"{r['collect_ms_median']} ms, exchange {r.get('exchange_ms_median')} ms, "
                      f"update {r['update_ms_median']} ms",
                      file=sys.stderr)
            for walk, ms in entry["model"].items():
                for m in ms:
                    print(f"  model ({walk} walk) {m['ranks']:3d} ranks: {m['frame_ms']} ms/frame, "
                          f"x{m['speedup']} ({m['bound']}-bound, imbalance {m['imbalance']})",
                          file=sys.stderr)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
