#!/usr/bin/env python3
"""Summary of scripts/tensorfield-suite (issue 31, Xu 2017): medians per variant, paired ratios of
tensorfield against each other variant with bootstrap intervals of the median and the share of
pairs below 1, and the targets of issue 31 that the runs can judge.

  scripts/tensorfield_suite_summary.py OUT_DIR      writes OUT_DIR/summary.json and summary.md
  scripts/tensorfield_suite_summary.py --self-test  checks the statistics on made-up runs
"""
import csv
import json
import pathlib
import statistics
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from taskflow_suite_summary import median_interval, num  # noqa: E402  (the same bootstrap)

METRICS = [("time_s", "time s"), ("distance_total_m", "travel m"),
           ("base_ang_accel_radps2", "|ang. acc.| rad/s²"), ("base_sharp_turns_per_10m", "sharp/10 m"),
           ("completeness_below_robot", "compl. <1.8 m"), ("blocked_paths", "blocked"),
           ("plan_ms_median", "plan ms")]
# Only in runs with tracked poses (VOXPLAN_SUITE_POSES=tracked).
TRACKED = ["registration_rms_m", "ate_rms_m", "frames_lost"]


def parse_name(name):
    """<scene>_<variant>_s<seed> -> (scene, variant, seed); variants hold no '_'."""
    head, _, seed = name.rpartition("_s")
    scene, _, variant = head.rpartition("_")
    return scene, variant, seed


def load(out):
    runs = []
    for d in sorted(p for p in pathlib.Path(out).iterdir() if (p / "metrics.json").exists()):
        scene, variant, seed = parse_name(d.name)
        runs.append({"scene": scene, "variant": variant, "seed": seed,
                     "m": json.loads((d / "metrics.json").read_text()), "dir": d})
    return runs


def key_frames(run):
    """The diagnostics of a run's key-frame calls (plan_calls.csv), as dicts of strings."""
    path = run["dir"] / "plan_calls.csv" if "dir" in run else None
    if path is None or not path.exists():
        return []
    with open(path, newline="") as f:
        rows = [dict(kv.split("=", 1) for kv in row.get("diagnostics", "").split(";") if "=" in kv)
                for row in csv.DictReader(f)]
    return [d for d in rows if "census_degenerate" in d]


def census(frames):
    """X Fig. 2 and 17 over one run's key frames: the degenerate points and the normal-oriented
    vector field's singularities from the same constraints (census_vector; census_vector_normal
    in runs before it), as medians per key frame and as the ratio of their sums (every key frame
    counts, also those where the vector field has none); with topology control, the median over
    key frames of the points after it over those before. None where a value is undefined."""
    points, singular, control = [], [], []
    for d in frames:
        t = float(d["census_degenerate"])
        n = float(d.get("census_vector", d.get("census_vector_normal", "-1")))
        if t >= 0 and n >= 0:
            points.append(t)
            singular.append(n)
        before, after = float(d.get("control_points_before", "-1")), float(d.get("control_points_after", "-1"))
        if before > 0 and after >= 0:
            control.append(after / before)
    return {"key_frames": len(points),
            "points": statistics.median(points) if points else None,
            "singularities": statistics.median(singular) if singular else None,
            "ratio": sum(points) / sum(singular) if sum(singular) > 0 else None,
            "control": statistics.median(control) if control else None}


def census_by_scene(runs):
    """census() of every tensorfield run, by scene: medians over the scene's runs."""
    out = {}
    for scene in sorted({r["scene"] for r in runs if r["variant"] == "tensorfield"}):
        per_run = [census(key_frames(r)) for r in runs
                   if r["variant"] == "tensorfield" and r["scene"] == scene]
        row = {"runs": len(per_run)}
        for key in ("points", "singularities", "ratio"):
            vals = [c[key] for c in per_run if c[key] is not None]
            row[key] = statistics.median(vals) if vals else None
        out[scene] = row
    return out


def medians(runs):
    out = {}
    for v in sorted({r["variant"] for r in runs}):
        rs = [r for r in runs if r["variant"] == v]
        row = {"runs": len(rs), "done": sum(r["m"].get("terminated") == "done" for r in rs) / len(rs)}
        for key, _ in METRICS:
            vals = [r["m"][key] for r in rs if num(r["m"].get(key))]
            row[key] = statistics.median(vals) if vals else None
        out[v] = row
    return out


def paired(runs, a, b, key):
    """Ratios a/b over runs sharing scene and seed: median, its interval, share below 1."""
    by = {(r["scene"], r["seed"]): r["m"].get(key) for r in runs if r["variant"] == b}
    ratios = []
    for r in runs:
        if r["variant"] != a:
            continue
        other = by.get((r["scene"], r["seed"]))
        mine = r["m"].get(key)
        if num(mine) and num(other) and other > 0:
            ratios.append(mine / other)
    if not ratios:
        return None
    lo, hi = median_interval(ratios)
    return {"pairs": len(ratios), "median": statistics.median(ratios), "ci95": [lo, hi],
            "below_1": sum(x < 1 for x in ratios) / len(ratios)}


def targets(runs, med):
    rows = []

    def add(label, comp, ok):
        rows.append({"target": label, "status": "n/a" if comp is None else ("met" if ok(comp) else "not met"),
                     "comparison": comp})
    t = paired(runs, "tensorfield", "notopo", "time_s")
    add("topology routing vs none: time <= 0.70, below 1 in >= 80 % of pairs", t,
        lambda c: c["median"] <= 0.70 and c["below_1"] >= 0.8)
    t = paired(runs, "tensorfield", "notopo", "distance_total_m")
    add("topology routing vs none: travel <= 0.80, below 1 in >= 80 % of pairs", t,
        lambda c: c["median"] <= 0.80 and c["below_1"] >= 0.8)
    # X T3: against the better (lower median) of the harmonic-function and potential-field
    # methods, all with the fixed forward camera (X L429).
    for key, label, bound in (("time_s", "time", 0.75), ("distance_total_m", "travel", 0.85)):
        base = [v for v in ("harmonic", "potential") if (med.get(v) or {}).get(key) is not None]
        best = min(base, key=lambda v: med[v][key]) if base else "harmonic"
        t = paired(runs, "fixedcam", best, key)
        add(f"vs the better of the harmonic and potential methods, same fixed camera: {label} <= "
            f"{bound} (fixedcam / {best})", t, lambda c, b=bound: c["median"] <= b)
    # Smoother than both vector fields from the same constraints (X Fig. 2, 13).
    for v in ("vecnormal", "vectangent"):
        t = paired(runs, "tensorfield", v, "base_ang_accel_radps2")
        add(f"smoother than the {v[3:]}-oriented vector field: |angular acceleration| ratio <= 0.8, "
            f"lower in >= 80 % of pairs (tensorfield / {v})", t,
            lambda c: c["median"] <= 0.8 and c["below_1"] >= 0.8)
    t = paired(runs, "tensorfield", "linear", "base_ang_accel_radps2")
    add("space-time smoother than linear in >= 70 % of pairs", t, lambda c: c["below_1"] >= 0.7)
    per_run = [c["ratio"] for c in (census(key_frames(r)) for r in runs if r["variant"] == "tensorfield")
               if c["ratio"] is not None]
    comp = {"median": statistics.median(per_run), "pairs": len(per_run)} if per_run else None
    add("degenerate points <= 0.5 x the vector fields' singularities from the same constraints "
        "(median over runs of each run's sum over its key frames)", comp, lambda c: c["median"] <= 0.5)
    per_run = [c["control"] for c in (census(key_frames(r)) for r in runs if r["variant"] == "control")
               if c["control"] is not None]
    comp = {"median": statistics.median(per_run), "pairs": len(per_run)} if per_run else None
    add("topology control: degenerate points after it <= 0.8 x before, per key frame (median over "
        "runs of the per-key-frame median)", comp, lambda c: c["median"] <= 0.8)
    # With tracked poses: registration (the tracker's residual) better with space-time than
    # linear interpolation and with the optimised camera than the fixed one.
    for v, label in (("linear", "space-time than linear"), ("fixedcam", "the optimised camera than a fixed one")):
        t = paired(runs, "tensorfield", v, "registration_rms_m")
        add(f"with tracked poses: registration residual lower with {label} (median of tensorfield / {v} < 1)",
            t, lambda c: c["median"] < 1)
    done = med.get("tensorfield", {}).get("done")
    rows.append({"target": ">= 90 % of tensorfield runs end done",
                 "status": "n/a" if done is None else ("met" if done >= 0.9 else "not met"),
                 "comparison": {"median": done}})
    c = med.get("tensorfield", {}).get("completeness_below_robot")
    rows.append({"target": "completeness of the observable surface below robot height >= 0.90 (median)",
                 "status": "n/a" if c is None else ("met" if c >= 0.9 else "not met"),
                 "comparison": {"median": c}})
    return rows


def fmt(x, d=3):
    return "-" if x is None else (f"{x:.{d}f}" if isinstance(x, float) else str(x))


def render(med, comps, tgts, fields=None):
    lines = ["## Medians per variant", "",
             "| variant | runs | done | " + " | ".join(label for _, label in METRICS) + " |",
             "|---" * (3 + len(METRICS)) + "|"]
    for v, row in med.items():
        lines.append(f"| {v} | {row['runs']} | {row['done'] * 100:.0f} % | " +
                     " | ".join(fmt(row[k]) for k, _ in METRICS) + " |")
    lines += ["", "## tensorfield / variant (paired medians, 95 % bootstrap interval, share of pairs below 1)", "",
              "| variant | metric | pairs | median | 95 % interval | below 1 |", "|---|---|---|---|---|---|"]
    for (v, key), c in comps.items():
        if c:
            lines.append(f"| {v} | {key} | {c['pairs']} | {c['median']:.3f} | "
                         f"{c['ci95'][0]:.3f} - {c['ci95'][1]:.3f} | {c['below_1'] * 100:.0f} % |")
    if fields:
        lines += ["", "## Field census of the tensorfield runs (X Fig. 2; medians over the scene's runs)", "",
                  "| scene | runs | degenerate points per key frame | vector singularities per key frame | "
                  "ratio of sums |", "|---|---|---|---|---|"]
        for scene, row in fields.items():
            lines.append(f"| {scene} | {row['runs']} | {fmt(row['points'], 1)} | "
                         f"{fmt(row['singularities'], 1)} | {fmt(row['ratio'], 2)} |")
    lines += ["", "## Targets (issue 31)", "", "| target | status | value |", "|---|---|---|"]
    for t in tgts:
        c = t["comparison"] or {}
        lines.append(f"| {t['target']} | {t['status']} | {fmt(c.get('median'))} |")
    return "\n".join(lines) + "\n"


def summarise(out):
    runs = load(out)
    med = medians(runs)
    keys = [key for key, _ in METRICS[:5]]
    if any("registration_rms_m" in r["m"] for r in runs):
        keys += TRACKED
    comps = {(v, key): paired(runs, "tensorfield", v, key)
             for v in med if v != "tensorfield" for key in keys}
    tgts = targets(runs, med)
    fields = census_by_scene(runs)
    text = render(med, comps, tgts, fields)
    print(text)
    pathlib.Path(out, "summary.json").write_text(json.dumps(
        {"runs": len(runs), "variants": med, "targets": tgts, "census": fields,
         "comparisons": {f"{v}:{k}": c for (v, k), c in comps.items()}}, indent=2) + "\n")
    pathlib.Path(out, "summary.md").write_text(f"# tensorfield-suite summary: {out}\n\n" + text)


def self_test():
    runs = []
    for seed in "123":
        for v, t in [("tensorfield", 50.0), ("notopo", 100.0)]:
            runs.append({"scene": "apt_R_1", "variant": v, "seed": seed,
                         "m": {"time_s": t * (1 + int(seed) / 100), "terminated": "done"}})
    c = paired(runs, "tensorfield", "notopo", "time_s")
    assert c["pairs"] == 3 and abs(c["median"] - 0.5) < 1e-12 and c["below_1"] == 1.0, c
    assert parse_name("apt_R_2_notopo_s3") == ("apt_R_2", "notopo", "3")
    assert parse_name("small-house-visual_tensorfield_s1") == ("small-house-visual", "tensorfield", "1")
    tg = targets(runs, medians(runs))
    assert tg[0]["status"] == "met", tg[0]
    assert all(t["status"] == "n/a" for t in tg if "registration" in t["target"]), tg
    for r in runs:
        r["m"]["registration_rms_m"] = 0.008 if r["variant"] == "tensorfield" else 0.010
        r["variant"] = "linear" if r["variant"] == "notopo" else r["variant"]
    reg = [t for t in targets(runs, medians(runs)) if "registration" in t["target"]]
    assert reg[0]["status"] == "met" and abs(reg[0]["comparison"]["median"] - 0.8) < 1e-12, reg
    assert reg[1]["status"] == "n/a", reg  # no fixedcam runs
    frames = [{"census_degenerate": "2", "census_vector": "0"},
              {"census_degenerate": "4", "census_vector": "8", "control_points_before": "4",
               "control_points_after": "2"},
              {"census_degenerate": "3", "census_vector_normal": "4"}]  # an older run's name
    c = census(frames)
    assert c["key_frames"] == 3 and c["points"] == 3 and c["singularities"] == 4, c
    assert abs(c["ratio"] - 9 / 12) < 1e-12 and c["control"] == 0.5, c
    assert census([{"census_degenerate": "2", "census_vector": "0"}])["ratio"] is None
    print("self-test passed")


if __name__ == "__main__":
    if sys.argv[1:] == ["--self-test"]:
        self_test()
    elif len(sys.argv) == 2:
        summarise(sys.argv[1])
    else:
        sys.exit(__doc__)
