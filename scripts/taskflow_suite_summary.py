#!/usr/bin/env python3
"""Summary of scripts/taskflow-suite (issue 30): medians per planner variant, paired ratios with
95 % bootstrap intervals, the issue's targets (met / not met / n/a), the completion's calibration
(Spearman rho of predicted against true per-object incompleteness) and the planning times.

    scripts/taskflow_suite_summary.py OUT_DIR [--team N]   # prints, writes summary.json/.md
    scripts/taskflow_suite_summary.py --self-test            # checks rho and the bootstrap

Run folders are named <scene>_<variant>_r<R>_s<seed> (variant names hold no '_'). Pairs share
scene and seed; a variant is paired at the team size (--team, default the most common robot
count), except nbo1, which runs 1 robot and whose time and distance are divided by the team size
(per-robot normalised, as Guo 2022 G L251 does). Plain Python: no numpy on the target machines.
"""
import argparse
import collections
import csv
import json
import math
import pathlib
import random
import statistics
import sys

RESAMPLES = 2000
ABLATIONS = ["noflow", "nosw-3e1r", "nosw-2e2r", "nosw-1e3r", "nore", "noex", "nocomp"]
VARIANT_ORDER = ["omt", "taskflow", *ABLATIONS, "nbo4", "nbo1"]
# The per-variant columns: metrics.json key and a short header.
FIELDS = [("o_comp_2cm", "O-Comp 2cm"), ("o_comp_5cm", "O-Comp 5cm"), ("o_rms_m", "O-RMS m"),
          ("time_s", "T-C s"), ("distance_total_m", "D-C m"), ("time_load_balance", "T-LB"),
          ("load_balance_cov", "D-LB"), ("mode_switches", "switches"),
          ("plan_ms_median", "plan ms")]
NAMES = dict(FIELDS)
DIGITS = {"o_rms_m": 4, "time_s": 1, "distance_total_m": 1, "mode_switches": 1, "plan_ms_median": 1}


# ---------------------------------------------------------------- statistics (plain Python)

def median_interval(values, resamples=RESAMPLES):
    # As scripts/explore-suite: percentile bootstrap of the median over the pairs, seeded, so
    # the same runs give the same interval: how far the median could move with another draw
    # of runs (one early plan that differs changes a whole run).
    rng = random.Random(0)
    medians = sorted(statistics.median(rng.choices(values, k=len(values)))
                     for _ in range(resamples))
    return [medians[int(0.025 * resamples)], medians[int(0.975 * resamples) - 1]]


def ranks(values):
    # 1-based ranks, ties given the average of the ranks they span (Spearman's convention).
    order = sorted(range(len(values)), key=lambda i: values[i])
    out = [0.0] * len(values)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and values[order[j + 1]] == values[order[i]]:
            j += 1
        for k in range(i, j + 1):
            out[order[k]] = (i + j) / 2 + 1
        i = j + 1
    return out


def spearman(x, y):
    # Pearson correlation of the ranks (exact with ties, unlike 1 - 6 sum d^2 / n(n^2-1)).
    # None when it is undefined: fewer than 2 points, or one side constant.
    if len(x) != len(y) or len(x) < 2:
        return None
    rx, ry = ranks(x), ranks(y)
    mx, my = statistics.fmean(rx), statistics.fmean(ry)
    sxy = sum((a - mx) * (b - my) for a, b in zip(rx, ry))
    sxx = sum((a - mx) ** 2 for a in rx)
    syy = sum((b - my) ** 2 for b in ry)
    if sxx == 0 or syy == 0:
        return None
    return sxy / math.sqrt(sxx * syy)


def percentile(values, q):  # linear interpolation, q in [0, 1]
    v = sorted(values)
    pos = q * (len(v) - 1)
    lo = math.floor(pos)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (pos - lo)


def num(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


# ---------------------------------------------------------------- loading the runs

def scene_group(scene):
    """apt_L_2 -> apt_L (the paper reports by house size); a scene file is its own group."""
    parts = scene.split("_")
    return "_".join(parts[:2]) if len(parts) == 3 and parts[0] == "apt" and parts[2].isdigit() else scene


def parse_name(name):
    """<scene>_<variant>_r<R>_s<seed> -> (scene, variant, R, seed), None if it is not a run."""
    try:
        head, seed = name.rsplit("_s", 1)
        head, r = head.rsplit("_r", 1)
        scene, variant = head.rsplit("_", 1)
        return scene, variant, int(r), int(seed)
    except ValueError:
        return None


def last_predictions(plan_calls):
    """The last obj_<id>_incompleteness of each object over a run's plan calls: the
    completion's final word on it (objects seen late have fewer calls)."""
    pred = {}
    with open(plan_calls, newline="") as f:
        for row in csv.DictReader(f):
            for item in (row.get("diagnostics") or "").split(";"):
                key, _, value = item.partition("=")
                if key.startswith("obj_") and key.endswith("_incompleteness"):
                    try:
                        pred[int(key[4:-len("_incompleteness")])] = float(value)
                    except ValueError:
                        pass
    return pred


def true_incompleteness(objects_csv):
    truth = {}
    with open(objects_csv, newline="") as f:
        for row in csv.DictReader(f):
            try:
                truth[int(row["id"])] = 1.0 - float(row["completeness_2cm"])
            except (KeyError, ValueError):
                pass
    return truth


def plan_call_ms(plan_calls):
    """Wall ms of every plan call, and of the calls that planned: those that generated tasks
    (their diagnostics name gen_exp_ms), not the ones the flow answered at once."""
    every, planned = [], []
    with open(plan_calls, newline="") as f:
        for r in csv.DictReader(f):
            if not r.get("elapsed_ms"):
                continue
            every.append(float(r["elapsed_ms"]))
            if "gen_exp_ms=" in r.get("diagnostics", ""):
                planned.append(float(r["elapsed_ms"]))
    return every, planned


def load(out):
    runs = []
    for m in sorted(out.glob("*/metrics.json")):
        key = parse_name(m.parent.name)
        if key is None:
            continue
        scene, variant, r, seed = key
        runs.append({"name": m.parent.name, "dir": m.parent, "scene": scene, "variant": variant,
                     "robots": r, "seed": seed, "m": json.loads(m.read_text())})
    return runs


# ---------------------------------------------------------------- the summary

class Summary:
    def __init__(self, runs, team):
        self.runs, self.team = runs, team
        for run in runs:  # nbo1: per-robot normalised time and distance (G L251)
            if run["variant"] == "nbo1":
                for k in ("time_s", "distance_total_m"):
                    if num(run["m"].get(k)):
                        run["m"][k] = run["m"][k] / team
        # The paired runs: one per (variant, scene, seed) at the team size (nbo1 at 1 robot).
        self.paired = {}
        for run in runs:
            if run["robots"] == (1 if run["variant"] == "nbo1" else team):
                self.paired[(run["variant"], run["scene"], run["seed"])] = run
        self.variants = sorted({r["variant"] for r in runs},
                               key=lambda v: (VARIANT_ORDER.index(v) if v in VARIANT_ORDER
                                              else len(VARIANT_ORDER), v))
        self.comparisons = {}

    def medians(self):
        groups = collections.defaultdict(list)
        for run in self.runs:
            groups[(run["variant"], run["robots"])].append(run["m"])
        rows = []
        for (variant, r), ms in sorted(groups.items(), key=lambda kv: (self.variants.index(kv[0][0]), kv[0][1])):
            row = {"variant": variant, "robots": r, "runs": len(ms),
                   "done_share": sum(m.get("terminated") == "done" for m in ms) / len(ms)}
            for f, _ in FIELDS + [("plan_ms_p90", ""), ("idle_time_s", "")]:
                vals = [m[f] for m in ms if num(m.get(f))]
                row[f + "_median"] = statistics.median(vals) if vals else None
            rows.append(row)
        return rows

    def compare(self, a, b, metric, kind="ratio", group=None):
        """Paired a / b (or, kind "gap", (a - b) / (1 - b)) over the runs sharing scene and seed
        (only the scenes of one scene group if given). None when no pair exists; pairs with a
        zero denominator are counted and left out."""
        key = (a, b, metric, kind, group)
        if key in self.comparisons:
            return self.comparisons[key]
        vals, av, bv, skipped, both_done = [], [], [], 0, 0
        for (variant, scene, seed), ra in sorted(self.paired.items()):
            rb = self.paired.get((b, scene, seed))
            if variant != a or rb is None or (group and scene_group(scene) != group):
                continue
            x, y = ra["m"].get(metric), rb["m"].get(metric)
            if not (num(x) and num(y)):
                continue
            den = (1 - y) if kind == "gap" else y
            if den == 0:
                skipped += 1
                continue
            vals.append((x - y) / den if kind == "gap" else x / y)
            av.append(x)
            bv.append(y)
            both_done += ra["m"].get("terminated") == "done" and rb["m"].get("terminated") == "done"
        entry = None
        if vals:
            entry = {"a": a, "b": b, "metric": metric, "kind": kind, "group": group, "pairs": len(vals),
                     "pairs_both_done": both_done, "pairs_zero_denominator": skipped,
                     "median": statistics.median(vals), "ci95": median_interval(vals),
                     # Single runs are chaotic, so the ratio of the means is given beside it.
                     "ratio_of_means": (statistics.fmean(av) / statistics.fmean(bv)
                                        if kind == "ratio" and statistics.fmean(bv) else None)}
        self.comparisons[key] = entry
        return entry

    def all_comparisons(self):
        tf = "taskflow"
        for f in ["o_comp_2cm", "o_rms_m", "time_s", "distance_total_m", "time_load_balance",
                  "load_balance_cov"]:
            self.compare(tf, "omt", f)
        self.compare(tf, "omt", "o_comp_2cm", "gap")
        for f in ["time_s", "time_load_balance", "o_comp_2cm"]:
            self.compare(tf, "noflow", f)
        for base in ["nbo1", "nbo4"]:
            for f in ["time_s", "distance_total_m", "o_comp_2cm"]:
                self.compare(tf, base, f)
        for abl in ABLATIONS:
            self.compare(tf, abl, "o_comp_2cm")
        # The G T3 orderings, as paired ratios (slower / faster side over the same runs).
        self.compare("nore", tf, "time_s")
        self.compare("noex", tf, "time_s")
        self.compare("nosw-2e2r", "nosw-3e1r", "time_s")
        self.compare("nosw-1e3r", "nosw-2e2r", "time_s")
        self.compare("noflow", tf, "time_load_balance")
        pooled = [e for e in self.comparisons.values() if e]
        # taskflow / omt per scene group (apartment size, the house), as G T1 has S / M / L.
        groups = sorted({scene_group(k[1]) for k in self.paired})
        by_group = []
        if len(groups) > 1:
            for g in groups:
                for f in ["o_comp_2cm", "o_rms_m", "time_s", "distance_total_m", "time_load_balance"]:
                    e = self.compare(tf, "omt", f, group=g)
                    if e:
                        by_group.append(e)
        return pooled, by_group

    def team_runs(self, variant):  # the variant's runs at the team size, as paired
        return [r for (v, _, _), r in sorted(self.paired.items()) if v == variant]

    def calibration(self, variant="taskflow"):
        """Spearman rho of the completion's predicted incompleteness (last value per object)
        against the true one, 1 - completeness_2cm, pooled over the variant's runs and per run.
        Objects in only one of the two (undetected, or merged into another id) are left out."""
        pooled_p, pooled_t, per_run = [], [], []
        for run in self.team_runs(variant):
            pc, oc = run["dir"] / "plan_calls.csv", run["dir"] / "objects.csv"
            if not pc.exists() or not oc.exists():
                continue
            pred, truth = last_predictions(pc), true_incompleteness(oc)
            ids = sorted(pred.keys() & truth.keys())
            if not ids:
                continue
            p, t = [pred[i] for i in ids], [truth[i] for i in ids]
            pooled_p += p
            pooled_t += t
            per_run.append({"run": run["name"], "objects": len(ids), "rho": spearman(p, t),
                            "predicted_only": len(pred.keys() - truth.keys()),
                            "true_only": len(truth.keys() - pred.keys())})
        rhos = [r["rho"] for r in per_run if r["rho"] is not None]
        return {"variant": variant, "objects": len(pooled_p), "runs": len(per_run),
                "rho_pooled": spearman(pooled_p, pooled_t),
                "rho_per_run_median": statistics.median(rhos) if rhos else None,
                "rho_per_run_ci95": median_interval(rhos) if rhos else None,
                "per_run": per_run}

    def planning(self, variant="taskflow"):
        # Per plan call, pooled over the variant's runs at the team size (plan_calls.csv),
        # beside the median of each run's own median (metrics.json).
        calls, planned, run_medians = [], [], []
        for run in self.team_runs(variant):
            if (run["dir"] / "plan_calls.csv").exists():
                every, some = plan_call_ms(run["dir"] / "plan_calls.csv")
                calls += every
                planned += some
            if num(run["m"].get("plan_ms_median")):
                run_medians.append(run["m"]["plan_ms_median"])
        if not planned:
            return None
        # The targets judge the calls that planned; most calls are the flow's "nothing to do"
        # (a robot still busy), whose microseconds would make any median look fast.
        return {"variant": variant, "calls": len(planned), "call_ms_median": statistics.median(planned),
                "call_ms_p90": percentile(planned, 0.9), "call_ms_max": max(planned),
                "all_calls": len(calls), "all_call_ms_median": statistics.median(calls),
                "run_median_ms_median": statistics.median(run_medians) if run_medians else None}


def fmt(x, digits=3):
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.{digits}f}" if abs(x) < 1e4 else f"{x:.0f}"
    return str(x)


def check(entry, op, threshold, label, source):
    """One target against a paired median: status met / not met / n/a, the number with its
    interval, and whether the interval straddles the threshold (inside the run-to-run spread)."""
    t = {"target": label, "source": source, "status": "n/a", "value": None, "ci95": None,
         "pairs": 0, "note": ""}
    if entry is None:
        t["note"] = "no paired runs"
        return t
    v, (lo, hi) = entry["median"], entry["ci95"]
    t.update(value=v, ci95=[lo, hi], pairs=entry["pairs"])
    if op == "in":
        a, b = threshold
        ok = a <= v <= b
        straddles = lo < a <= hi or lo <= b < hi
    else:
        ok = {"<=": v <= threshold, ">=": v >= threshold, "<": v < threshold, ">": v > threshold}[op]
        straddles = lo <= threshold <= hi
    t["status"] = "met" if ok else "not met"
    notes = []
    if straddles:
        notes.append("interval straddles the threshold")
    if entry["metric"] == "time_s" and entry["pairs_both_done"] < entry["pairs"]:
        # A run stopped by --max-time has time_s = the limit: its time ratio is censored.
        notes.append(f"{entry['pairs'] - entry['pairs_both_done']} pair(s) hit the time limit")
    if entry["pairs_zero_denominator"]:
        notes.append(f"{entry['pairs_zero_denominator']} pair(s) with a zero denominator left out")
    t["note"] = "; ".join(notes)
    return t


def targets(s, calib, plan):
    tf, c = "taskflow", s.compare
    out = []
    # taskflow / omt, O-Comp: the ratio, or the gap closed when omt is already near the ceiling.
    oc, gap = c(tf, "omt", "o_comp_2cm"), c(tf, "omt", "o_comp_2cm", "gap")
    omt_oc = [r["m"]["o_comp_2cm"] for k, r in s.paired.items() if k[0] == "omt" and num(r["m"].get("o_comp_2cm"))]
    high = bool(omt_oc) and statistics.median(omt_oc) > 0.85
    t = check(oc, ">=", 1.20, "taskflow/omt O-Comp 2cm >= 1.20 (or gap closed >= 0.25 if omt > 0.85)", "issue 30")
    if high and gap is not None:
        g = check(gap, ">=", 0.25, "", "")
        if g["status"] == "met":
            t["status"] = "met"
        t["note"] = "; ".join(x for x in [t["note"], f"omt O-Comp median {statistics.median(omt_oc):.3f} > 0.85: "
                                          f"gap closed {gap['median']:.3f} [{gap['ci95'][0]:.3f}, {gap['ci95'][1]:.3f}]"] if x)
    elif gap is not None:
        t["note"] = "; ".join(x for x in [t["note"], f"gap closed {gap['median']:.3f}"] if x)
    out.append(t)
    out.append(check(c(tf, "omt", "o_rms_m"), "<=", 0.90, "taskflow/omt O-RMS <= 0.90", "issue 30"))
    out.append(check(c(tf, "omt", "time_s"), "<=", 0.90, "taskflow/omt T-C <= 0.90", "issue 30"))
    out.append(check(c(tf, "omt", "distance_total_m"), "in", (0.95, 1.35), "taskflow/omt D-C in [0.95, 1.35]", "issue 30"))
    out.append(check(c(tf, "omt", "time_load_balance"), "<=", 0.50, "taskflow/omt T-LB <= 0.50", "issue 30"))
    out.append(check(c(tf, "omt", "load_balance_cov"), "<=", 1.10, "taskflow/omt D-LB <= 1.10", "design F.4"))
    out.append(check(c(tf, "noflow", "time_s"), "<=", 0.90, "taskflow/noflow T-C <= 0.90", "issue 30"))
    out.append(check(c(tf, "noflow", "time_load_balance"), "<=", 0.60, "taskflow/noflow T-LB <= 0.60", "issue 30"))
    out.append(check(c(tf, "noflow", "o_comp_2cm"), ">=", 1.00, "taskflow/noflow O-Comp >= 1.00", "design F.4"))
    out.append(check(c("nore", tf, "time_s"), "<", 1.0, "T-C(nore) < T-C(taskflow): nore/taskflow T-C < 1", "issue 30 (G T3)"))
    out.append(check(c("noex", tf, "time_s"), ">", 1.0, "T-C(taskflow) < T-C(noex): noex/taskflow T-C > 1", "issue 30 (G T3)"))
    out.append(check(c("nosw-2e2r", "nosw-3e1r", "time_s"), ">", 1.0, "T-C(3e1r) < T-C(2e2r): 2e2r/3e1r T-C > 1", "issue 30 (G T3)"))
    out.append(check(c("nosw-1e3r", "nosw-2e2r", "time_s"), ">", 1.0, "T-C(2e2r) < T-C(1e3r): 1e3r/2e2r T-C > 1", "issue 30 (G T3)"))
    for abl in ABLATIONS:
        out.append(check(c(tf, abl, "o_comp_2cm"), ">=", 1.05, f"taskflow/{abl} O-Comp >= 1.05", "issue 30 (G T3)"))
    out.append(check(c("noflow", tf, "time_load_balance"), ">=", 1.5, "T-LB(noflow) >= 1.5 T-LB(taskflow): noflow/taskflow T-LB >= 1.5", "design F.4"))
    out.append(check(c(tf, "nbo1", "time_s"), "<=", 0.70, "taskflow/nbo1 T-C (per robot) <= 0.70", "design F.4"))
    out.append(check(c(tf, "nbo1", "distance_total_m"), "<=", 0.95, "taskflow/nbo1 D-C (per robot) <= 0.95", "design F.4"))
    out.append(check(c(tf, "nbo1", "o_comp_2cm"), ">=", 0.95, "taskflow/nbo1 O-Comp >= 0.95", "design F.4"))
    # Not paired ratios: the calibration and the planning time of taskflow itself.
    t = {"target": "completion ranking: Spearman rho (pooled) >= 0.5", "source": "issue 30",
         "status": "n/a", "value": calib["rho_pooled"], "ci95": calib["rho_per_run_ci95"],
         "pairs": calib["objects"], "note": "no taskflow objects with predictions"}
    if calib["rho_pooled"] is not None:
        t["status"] = "met" if calib["rho_pooled"] >= 0.5 else "not met"
        t["note"] = (f"{calib['objects']} objects over {calib['runs']} run(s); per-run median "
                     f"{fmt(calib['rho_per_run_median'])} (interval is of that median)")
    out.append(t)
    for label, key, limit, source in [("planning: median per call <= 0.3 s", "call_ms_median", 300.0, "issue 30"),
                                      ("planning: p90 per call <= 1.0 s", "call_ms_p90", 1000.0, "design F.4")]:
        t = {"target": label, "source": source, "status": "n/a", "value": None, "ci95": None,
             "pairs": 0, "note": "no taskflow plan calls"}
        if plan:
            t.update(value=plan[key] / 1000, pairs=plan["calls"], status="met" if plan[key] <= limit else "not met",
                     note=f"seconds, over the {plan['calls']} calls that planned (of {plan['all_calls']}) "
                          f"at {s.team} robots; wall time, machine load included")
        out.append(t)
    return out


# ---------------------------------------------------------------- rendering

def table(header, rows):
    # A markdown table padded to line up in a terminal too: the same text goes to summary.md.
    cells = [header] + [[fmt(x) for x in r] for r in rows]
    w = [max(len(row[i]) for row in cells) for i in range(len(header))]
    line = lambda row: "| " + " | ".join(x.ljust(w[i]) for i, x in enumerate(row)) + " |"
    return "\n".join([line(cells[0]), "|" + "|".join("-" * (x + 2) for x in w) + "|"] + [line(r) for r in cells[1:]])


def render(s, med, comps, by_group, tgts, calib, plan):
    parts = [f"## Medians per variant ({len(s.runs)} runs; pairs at {s.team} robots)\n"]
    parts.append(table(["variant", "R", "runs", "done"] + [h for _, h in FIELDS],
                       [[r["variant"] + (" *" if r["variant"] == "nbo1" else ""), r["robots"], r["runs"],
                         f"{100 * r['done_share']:.0f} %"] + [fmt(r[f + "_median"], DIGITS.get(f, 3)) for f, _ in FIELDS]
                        for r in med]))
    if any(r["variant"] == "nbo1" for r in med):
        parts.append(f"\n\\* nbo1 runs 1 robot; its T-C and D-C are divided by {s.team} (per-robot "
                     "normalised, as Guo 2022 G L251), here and in every ratio.")
    parts.append("\nO-Comp: object completeness at 2 / 5 cm; O-RMS: object RMS (m); T-C: time (s); "
                 "D-C: total distance (m); T-LB: time load balance (waiting share); D-LB: distance "
                 "load balance (CoV); done: share of runs that ended `done` (others hit --max-time, "
                 "so their T-C is the limit).")
    parts.append(f"\n## Paired ratios (median over runs sharing scene and seed, 95 % bootstrap "
                 f"interval of the median, {RESAMPLES} resamples, seed 0)\n")
    rows = []
    for e in comps:
        what = f"{e['a']} / {e['b']}" if e["kind"] == "ratio" else f"gap closed ({e['a']} - {e['b']}) / (1 - {e['b']})"
        rows.append([what, NAMES.get(e["metric"], e["metric"]), e["pairs"], e["median"],
                     f"{e['ci95'][0]:.3f} - {e['ci95'][1]:.3f}", e["ratio_of_means"], e["pairs_both_done"]])
    parts.append(table(["comparison", "metric", "pairs", "median", "95 % interval", "of means", "both done"], rows)
                 if rows else "(no pairs)")
    if by_group:
        parts.append("\n## taskflow / omt per scene group (paired medians, 95 % interval)\n")
        gs = sorted({e["group"] for e in by_group})
        fs = [f for f in ["o_comp_2cm", "o_rms_m", "time_s", "distance_total_m", "time_load_balance"]
              if any(e["metric"] == f for e in by_group)]
        cell = {(e["group"], e["metric"]): f"{e['median']:.3f} ({e['ci95'][0]:.3f}-{e['ci95'][1]:.3f}, n {e['pairs']})"
                for e in by_group}
        parts.append(table(["scenes"] + [NAMES[f] for f in fs], [[g] + [cell.get((g, f), "-") for f in fs] for g in gs]))
    parts.append("\n## Targets (issue 30; design F.4)\n")
    parts.append(table(["target", "status", "value", "95 % interval", "n", "note"],
                       [[t["target"], t["status"], t["value"],
                         f"{t['ci95'][0]:.3f} - {t['ci95'][1]:.3f}" if t["ci95"] else "-", t["pairs"], t["note"]]
                        for t in tgts]))
    n = collections.Counter(t["status"] for t in tgts)
    parts.append(f"\n{n['met']} met, {n['not met']} not met, {n['n/a']} n/a (a variant without runs).")
    parts.append("\n## Completion calibration (taskflow)\n")
    parts.append(f"Spearman rho of the predicted incompleteness (last `obj_<id>_incompleteness` of "
                 f"plan_calls.csv) against 1 - completeness_2cm (objects.csv): pooled "
                 f"{fmt(calib['rho_pooled'])} over {calib['objects']} objects in {calib['runs']} run(s); "
                 f"median per run {fmt(calib['rho_per_run_median'])}.")
    if plan:
        parts.append(f"\nPlanning (taskflow, {plan['calls']} calls that planned, of {plan['all_calls']}): "
                     f"median {plan['call_ms_median']:.1f} ms, p90 {plan['call_ms_p90']:.1f} ms, "
                     f"max {plan['call_ms_max']:.1f} ms per call; over every call the median is "
                     f"{plan['all_call_ms_median']:.1f} ms.")
    return "\n".join(parts) + "\n"


def summarise(out, team):
    runs = load(out)
    if not runs:
        print(f"no runs in {out}", file=sys.stderr)
        return 1
    if team is None:  # the most common team size among the runs that are not nbo1
        counts = collections.Counter(r["robots"] for r in runs if r["variant"] != "nbo1")
        team = counts.most_common(1)[0][0] if counts else 4
    s = Summary(runs, team)
    med = s.medians()
    comps, by_group = s.all_comparisons()
    calib = s.calibration()
    plan = s.planning()
    tgts = targets(s, calib, plan)
    text = render(s, med, comps, by_group, tgts, calib, plan)
    print(text)
    summary = {"runs": len(runs), "team": team, "resamples": RESAMPLES,
               "nbo1_normalisation": f"time_s and distance_total_m divided by {team} (G L251)",
               "variants": med, "comparisons": comps, "taskflow_vs_omt_by_scene_group": by_group, "targets": tgts, "calibration": calib,
               "planning": plan}
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    (out / "summary.md").write_text(f"# taskflow-suite summary: {out}\n\n" + text)
    print(f"wrote {out / 'summary.json'} and {out / 'summary.md'}")
    return 0


def self_test():
    close = lambda a, b: a is not None and abs(a - b) < 1e-9
    assert close(spearman([1, 2, 3, 4], [10, 20, 30, 40]), 1.0)
    assert close(spearman([1, 2, 3, 4], [0.9, 0.5, 0.2, 0.1]), -1.0)
    assert close(spearman([1, 2, 3, 4, 5], [1, 4, 9, 16, 25]), 1.0)  # monotone, not linear
    assert close(spearman([1, 2, 3, 4, 5], [2, 1, 4, 3, 5]), 0.8)    # 1 - 6*4/120
    assert ranks([10, 20, 20, 30]) == [1, 2.5, 2.5, 4]               # ties share their mean rank
    assert ranks([3, 1, 3, 3]) == [3, 1, 3, 3]
    assert close(spearman([1, 2, 3, 4], [1, 1, 2, 2]), 4 / math.sqrt(20))  # ties: Pearson of ranks
    assert close(spearman([1, 1, 2, 2], [5, 5, 7, 7]), 1.0)
    assert spearman([1, 2, 3], [5, 5, 5]) is None and spearman([1], [2]) is None
    assert median_interval([0.8] * 7) == [0.8, 0.8]
    lo, hi = median_interval([1.0, 2.0, 3.0, 4.0, 5.0])
    assert 1.0 <= lo <= 3.0 <= hi <= 5.0 and lo < hi
    assert median_interval([1.0, 2.0, 3.0, 4.0, 5.0]) == [lo, hi]     # seeded: the same again
    lo, hi = median_interval([1.1] * 20 + [0.9, 1.3])
    assert close(lo, 1.1) and close(hi, 1.1)                         # outliers barely move a median
    assert close(percentile([1, 2, 3, 4, 5], 0.9), 4.6)
    assert parse_name("apt_L_1_nosw-3e1r_r4_s3") == ("apt_L_1", "nosw-3e1r", 4, 3)
    assert parse_name("small_house_visual_nbo1_r1_s2") == ("small_house_visual", "nbo1", 1, 2)
    assert parse_name("configs") is None
    print("self-test passed")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", nargs="?", type=pathlib.Path, help="the suite's OUT_DIR")
    ap.add_argument("--team", type=int, help="robots per paired run (default: the most common)")
    ap.add_argument("--self-test", action="store_true", help="check rho and the bootstrap, then exit")
    a = ap.parse_args()
    if a.self_test:
        return self_test()
    if a.out is None:
        ap.error("OUT_DIR is required")
    return summarise(a.out, a.team)


if __name__ == "__main__":
    sys.exit(main())
