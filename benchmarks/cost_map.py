#!/usr/bin/env python
"""What a case costs over the whole design space, per preset and per scene: the loop's cost model.

The loop's acquisition and its replay price a case with the planned-cost law
(``spreadmap.loop.cost``: CPU = a N^b S^c of the spheres N and steps S the scene plans). This
benchmark evaluates that law at ``--points`` scrambled Sobol' points of the config's design box
(``scipy.stats.qmc.Sobol``, seed 0) for every preset, and prints per preset the mean, median, 90th
percentile and maximum CPU per case, max / median, and the share of the CPU spent at h/d >= 3.

With ``--measured CSV`` (a ``benchmarks/precision.py`` cases table) each scene (``--tree``: a
source tree, this one by default, or an arm of that table) is anchored to this machine: its law
is rescaled by the median of ln(measured / law) over its own measured cases, so that a scene whose
measured CPU departs from its plan (a per-step check the plan does not count) is priced as
measured. Two scenes priced so give the ratio of their mean CPU over the design space, with a 95 %
interval from resampling the two arms' cases paired by point and seed (the anchors' uncertainty;
the law's exponents are held fixed).

    .venv/bin/python benchmarks/cost_map.py                                   # this tree, every preset
    .venv/bin/python benchmarks/cost_map.py --measured docs/case_cost/final_cases.csv \\
        --arm shipped=. --arm issue31_start=RUNS/cost31/tree-dd28def --csv docs/case_cost/cost_map.csv

An arm's tree is read in a subprocess with that tree first on PYTHONPATH (its own scene code and
config), so an older revision plans its cases as it did.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

from spreadmap.loop.cost import DEFAULT_LAW

ROOT = Path(__file__).resolve().parents[1]

NAMES = ("f", "d_um", "h_um", "v_mm_s")

# Run inside an arm's tree: its config and scene plan the points (older trees kept the scene in
# spreadmap/scene.py, before spreadmap/case/).
PLAN = r"""
import json, sys
from pathlib import Path
try:
    from spreadmap.case.scene import scene_parameters
except ImportError:
    from spreadmap.scene import scene_parameters
from spreadmap import config as cfgmod
job = json.loads(sys.argv[1])
config = cfgmod.load(Path(job["tree"]) / "config.yaml")
if job.get("ranges_only"):
    print(json.dumps({"ranges": config["ranges"], "presets": list(config["presets"])}))
    raise SystemExit
out = {}
for preset in job["presets"]:
    rows = []
    for p in job["points"]:
        params = scene_parameters(dict(zip(("f", "d_um", "h_um", "v_mm_s"), p)), preset, dict(config), "cost")
        rows.append([params["n_particles"], params["estimated_steps"]])
    out[preset] = rows
print(json.dumps(out))
"""


def in_tree(tree: Path, job: dict) -> dict:
    env = {"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"}
    done = subprocess.run([sys.executable, "-c", PLAN, json.dumps({**job, "tree": str(tree)})], env=env, cwd=tree,
                          capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"planning in {tree} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout)


def sobol_points(ranges: dict, n: int, seed: int = 0) -> np.ndarray:
    from scipy.stats import qmc

    unit = qmc.Sobol(d=len(NAMES), scramble=True, seed=seed).random(n)
    lo = np.array([ranges[k]["min"] for k in NAMES], float)
    hi = np.array([ranges[k]["max"] for k in NAMES], float)
    return lo + unit * (hi - lo)


def law_seconds(work: np.ndarray, law: dict = DEFAULT_LAW) -> np.ndarray:
    work = np.asarray(work, float)
    return np.exp(law["ln_a"] + law["b_particles"] * np.log(work[:, 0]) + law["b_steps"] * np.log(work[:, 1]))


def summary(cpu: np.ndarray, h_over_d: np.ndarray) -> dict:
    med = float(np.median(cpu))
    return {"mean": float(np.mean(cpu)), "median": med, "p90": float(np.percentile(cpu, 90)),
            "max": float(np.max(cpu)), "max_over_median": float(np.max(cpu) / med),
            "share_cpu_wide": float(cpu[h_over_d >= 3].sum() / cpu.sum()), "share_cases_wide": float(np.mean(h_over_d >= 3))}


def measured_anchor(rows: list[dict], arm: str, tree: Path) -> tuple[np.ndarray, list[str]]:
    """ln(measured CPU / law) for each of the arm's ok cases, and their keys (point:seed)."""
    mine = [r for r in rows if r["arm"] == arm and r["status"] == "ok" and r["cpu_time"] not in ("", "nan")]
    if not mine:
        raise SystemExit(f"--measured has no finished case of arm {arm!r}")
    presets = sorted({r.get("preset") or "default" for r in mine})
    if presets != ["default"]:
        raise SystemExit(f"arm {arm!r}: the anchor reads `default` cases only (found {presets})")
    pts = [[float(r[k]) for k in NAMES] for r in mine]
    work = np.array(in_tree(tree, {"presets": ["default"], "points": pts})["default"], float)
    keys = [f"{r['point']}:{r.get('seed', '')}" for r in mine]
    return np.log([float(r["cpu_time"]) for r in mine]) - np.log(law_seconds(work)), keys


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=1024, help="Sobol' points (a power of 2)")
    ap.add_argument("--presets", nargs="+", help="presets to price (default: every preset of each tree's config)")
    ap.add_argument("--arm", action="append", default=[], metavar="NAME=TREE",
                    help="a scene to price: a name (an arm of --measured) and its source tree; default shipped=.")
    ap.add_argument("--measured", help="benchmarks/precision.py cases CSV: anchors each arm's law to its measured CPU")
    ap.add_argument("--boot", type=int, default=2000, help="bootstrap resamples of the benchmark points")
    ap.add_argument("--csv", help="one row per arm and preset")
    ap.add_argument("--json", help="the same, with the anchors and the mean ratio")
    args = ap.parse_args(argv)
    arms = [a.split("=", 1) for a in (args.arm or ["shipped=."])]
    arms = [(name, (ROOT / tree).resolve() if not Path(tree).is_absolute() else Path(tree)) for name, tree in arms]
    rows = list(csv.DictReader(open(args.measured))) if args.measured else []

    ranges = in_tree(arms[0][1], {"ranges_only": True})["ranges"]
    X = sobol_points(ranges, args.points)
    h_over_d = X[:, 2] / X[:, 1]
    print(f"{args.points} scrambled Sobol' points (seed 0) of the box {json.dumps(ranges)}; "
          f"h/d >= 3 at {np.mean(h_over_d >= 3):.0%} of them")
    print(f"law: ln_a {DEFAULT_LAW['ln_a']}, N^{DEFAULT_LAW['b_particles']}, S^{DEFAULT_LAW['b_steps']} "
          "(law seconds: the law's median machine)")
    out, per_point = [], {}
    for name, tree in arms:
        presets = args.presets or in_tree(tree, {"ranges_only": True})["presets"]
        work = in_tree(tree, {"presets": presets, "points": X.tolist()})
        anchor = None
        if rows:
            lr, names = measured_anchor(rows, name, tree)
            sd = float(np.std(lr, ddof=1)) if len(lr) > 1 else math.nan
            anchor = {"median_ln_ratio": float(np.median(lr)), "sd_ln_ratio": sd, "cases": len(lr),
                      "ln_ratio": lr.tolist(), "points": names}
        for preset in presets:
            w = np.array(work[preset], float)
            cpu = law_seconds(w)
            row = {"arm": name, "preset": preset, "scale": "law", **summary(cpu, h_over_d),
                   "median_spheres": float(np.median(w[:, 0])), "median_steps": float(np.median(w[:, 1]))}
            out.append(row)
            if anchor and preset == "default":
                per_point[name] = (cpu, anchor)
                out.append({**row, "scale": "this machine", **summary(cpu * math.exp(anchor["median_ln_ratio"]), h_over_d)})
    print()
    print("| scene | preset | seconds | mean | median | p90 | max | max / median | CPU at h/d >= 3 | median spheres "
          "| median steps |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in out:
        print(f"| {r['arm']} | {r['preset']} | {r['scale']} | {r['mean']:.1f} | {r['median']:.1f} | {r['p90']:.1f} | "
              f"{r['max']:.0f} | "
              f"{r['max_over_median']:.1f} | {r['share_cpu_wide']:.0%} | {r['median_spheres']:.0f} | {r['median_steps']:.0f} |")
    ratio = None
    if len(per_point) == 2:
        (a, (cpu_a, anc_a)), (b, (cpu_b, anc_b)) = per_point.items()
        # the two arms' cases paired by point and seed (interleaved in one run): resampling the pairs
        # keeps each point's share of both anchors
        ka, kb = dict(zip(anc_a["points"], anc_a["ln_ratio"])), dict(zip(anc_b["points"], anc_b["ln_ratio"]))
        keys = sorted(set(ka) & set(kb))
        if not keys:
            raise SystemExit(f"arms {a} and {b} share no (point, seed) in --measured")
        la, lb = np.array([ka[k] for k in keys]), np.array([kb[k] for k in keys])
        base = float(np.mean(cpu_a) / np.mean(cpu_b))
        est = base * math.exp(np.median(la) - np.median(lb))
        rng = np.random.default_rng(0)
        boot = []
        for _ in range(args.boot):
            i = rng.integers(0, len(keys), len(keys))
            boot.append(base * math.exp(np.median(la[i]) - np.median(lb[i])))
        lo, hi = np.percentile(boot, [2.5, 97.5])
        ratio = {"numerator": a, "denominator": b, "law_ratio": base, "ratio": est, "ci95": [float(lo), float(hi)],
                 "pairs": len(keys)}
        print(f"\nmean CPU per case over the box, {a} / {b}: law {base:.3f}; anchored to the measured cases {est:.3f} "
              f"(95 % {lo:.3f}-{hi:.3f}, bootstrap of the {len(keys)} cases paired by point and seed)")
        for name, (_, anc) in per_point.items():
            print(f"  {name}: measured / law, median {math.exp(anc['median_ln_ratio']):.3f} over {anc['cases']} cases "
                  f"(SD of ln {anc['sd_ln_ratio']:.3f})")
    if args.csv:
        keys = ["arm", "preset", "scale", "mean", "median", "p90", "max", "max_over_median", "share_cpu_wide",
                "share_cases_wide", "median_spheres", "median_steps"]
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
            w.writeheader()
            w.writerows(out)
    if args.json:
        Path(args.json).write_text(json.dumps({"points": args.points, "ranges": ranges, "law": DEFAULT_LAW,
                                               "rows": out, "anchors": {k: v[1] for k, v in per_point.items()},
                                               "mean_ratio": ratio}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
