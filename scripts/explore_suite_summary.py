#!/usr/bin/env python3
"""Summary of scripts/explore-suite OUT_DIR: medians per planner and team size, OMT / baseline
paired ratios with bootstrap intervals; writes OUT_DIR/summary.json."""
import json, pathlib, random, statistics, sys
out = pathlib.Path(sys.argv[1])
runs = {}
for m in sorted(out.glob("*/metrics.json")):
    runs[m.parent.name] = json.loads(m.read_text())

def key(name):  # scene, planner, robots, seed: <scene>_<planner>_r<R>_s<seed>
    head, rest = name.rsplit("_r", 1)
    scene, planner = head.rsplit("_", 1)
    r, seed = rest.split("_s")
    return scene, planner, int(r), int(seed)

fields = ["completeness", "accuracy_rms_m", "distance_per_area", "distance_total_m",
          "load_balance_cov", "time_s", "plan_ms_median"]
groups = {}
for name, m in runs.items():
    scene, planner, r, seed = key(name)
    groups.setdefault((planner, r), []).append((scene, seed, m))

summary = {"runs": len(runs), "groups": []}
print(f"{'planner':16} {'R':>2} {'runs':>4} {'done':>4} " + " ".join(f"{f:>17}" for f in fields))
for (planner, r), items in sorted(groups.items()):
    row = {"planner": planner, "robots": r, "runs": len(items),
           "terminated_done": sum(m.get("terminated") == "done" for _, _, m in items)}
    for f in fields:
        vals = [m[f] for _, _, m in items if isinstance(m.get(f), (int, float))]
        row[f + "_median"] = statistics.median(vals) if vals else None
    summary["groups"].append(row)
    print(f"{planner:16} {r:>2} {len(items):>4} {row['terminated_done']:>4} " +
          " ".join(f"{row[f + '_median']:>17.4f}" if row[f + '_median'] is not None else f"{'-':>17}"
                   for f in fields))

def median_interval(values, resamples=2000):
    # Percentile bootstrap of the median over the pairs, seeded: how far the median could move
    # with another draw of runs (one early plan that differs changes a whole run).
    rng = random.Random(0)
    medians = sorted(statistics.median(rng.choices(values, k=len(values)))
                     for _ in range(resamples))
    return [medians[int(0.025 * resamples)], medians[int(0.975 * resamples) - 1]]

# OMT against each baseline on the same scene, seed and robot count.
for base in sorted({k[0] for k in groups} - {"omt"}):
    for r in sorted({k[1] for k in groups}):
        ratios, comp_delta, dist, base_dist = [], [], [], []
        for name, m in runs.items():
            scene, planner, rr, seed = key(name)
            if planner != "omt" or rr != r:
                continue
            other = runs.get(f"{scene}_{base}_r{r}_s{seed}")
            if not other or not other.get("distance_per_area"):
                continue
            ratios.append(m["distance_per_area"] / other["distance_per_area"])
            comp_delta.append(m["completeness"] - other["completeness"])
            dist.append(m["distance_per_area"])
            base_dist.append(other["distance_per_area"])
        if ratios:
            # Single runs are chaotic (one different plan early changes the rest), so the means
            # are given beside the medians.
            entry = {"vs": base, "robots": r, "pairs": len(ratios),
                     "distance_per_area_ratio_median": statistics.median(ratios),
                     "distance_per_area_ratio_of_means": statistics.mean(dist) / statistics.mean(base_dist),
                     "completeness_delta_median": statistics.median(comp_delta),
                     "completeness_delta_mean": statistics.mean(comp_delta)}
            entry["distance_per_area_ratio_median_ci95"] = median_interval(ratios)
            summary.setdefault("omt_vs", []).append(entry)
            lo, hi = entry["distance_per_area_ratio_median_ci95"]
            print(f"omt/{base} R={r}: distance/area ratio median {entry['distance_per_area_ratio_median']:.3f} "
                  f"(95 % interval {lo:.3f}-{hi:.3f}; of means {entry['distance_per_area_ratio_of_means']:.3f}) over {len(ratios)} pairs, "
                  f"completeness delta median {entry['completeness_delta_median']:+.4f} "
                  f"(mean {entry['completeness_delta_mean']:+.4f})")
(out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
print(json.dumps(summary))
