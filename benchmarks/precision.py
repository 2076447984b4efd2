#!/usr/bin/env python
"""Information per CPU-second of one DEM case, 1 / (CV^2 x CPU s), for three scenes run interleaved:

  today      the scene and `default` preset of an earlier revision (--today-rev, the scene as it
             landed before the precision work: flat floor, fixed window);
  physics    this tree's scene with the new physics (config.yaml's scene: rough substrate) but the
             old fixed-window `default` preset (5 d bed, 6 d pile, 8 d window after a 3 d transient);
  precision  the new physics and the `default` preset sized by its precision target (target_cv) as
             first benchmarked: the steady-flow window (>= 1 d beyond the pile, >= 4 d long), c = 0.45;
  precision_slow_settle  the same with the old settle and relax (4 fidelity points, same seeds);
  window8    the window opens 3 d beyond the pile and lasts >= 8 d and until (c / target_cv)^2
             spheres have passed, c calibrated on the rough substrate; no standing reserve;
  shipped    this tree as shipped: window8 with the pile's standing reserve (scene.pile_reserve).

CV is the seed-to-seed relative SD of MFR (and PD) at a design point; CPU s the mean CPU time of
the YADE process per case. The points are eight design points spanning the space (the corners
d = 10 um / h = 75 um and d = 50 um / h = 55 um among them), each with --seeds packing seeds; the
jobs are interleaved (point by point, seed by seed, every arm's case queued before the next seed)
so that the machine's load falls on every arm alike. Each case is rendered by its own tree's
spreadmap (a subprocess with that tree on PYTHONPATH) and run by this tree's launcher; MFR, PD and
the per-case noise estimate are computed from every raw result by this tree's spreadmap.metrics.

Prints a table per point and the ratios against `today` with bootstrap 95 % intervals (seeds
resampled within each point), and writes one row per case (--csv) and the summary (--summary).
`--recompute DIR` re-reads a kept run's raw results instead of running anything.

    .venv/bin/python benchmarks/precision.py --seeds 1 2 3 4 --keep /tmp/precision --csv docs/precision/cases.csv \
        --summary docs/precision/summary.md
"""
from __future__ import annotations

import argparse
import csv
import io
import json
import math
import multiprocessing
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from spreadlab.study.checksums import republish_if_listed, verified_bytes
from spreadmap.files import write_csv_atomically
from spreadmap.targets import current_name
from spreadmap.targets import names as target_names

ROOT = Path(__file__).resolve().parent.parent

POINTS = {  # f, d_um, h_um, v_mm_s: the four fidelity points, the two corners, two more
    "normal": (0.30, 30, 65, 10),
    "narrow_gap_large": (0.45, 50, 55, 5),
    "small_diameter": (0.30, 20, 60, 15),
    "low_friction_fast": (0.15, 40, 75, 15),
    "coarse_thick_slow": (0.15, 50, 75, 5),
    "narrow_fast": (0.40, 25, 55, 15),
    "middle": (0.22, 35, 70, 7),
    "fine_thick_corner": (0.30, 10, 75, 10),  # last: the costliest case of today's scene
}
DEFAULT_POINTS = list(POINTS)
# the floor issue's points (issue 36: its table of the rough against the flat floor, 3 seeds each)
FLOOR_POINTS = {
    "floor_fine": (0.30, 29, 57, 10),
    "floor_coarse": (0.45, 45, 61, 6),
    "floor_thin_slippery": (0.15, 50, 55, 15),  # h/d 1.1: the full pile drained on the flat floor
}
POINTS.update(FLOOR_POINTS)
OLD_DEFAULT = {"width_d": 5, "heap_height_d": 10, "pile_length_min_d": 6, "heap_reserve": 1.5, "transient_d": 3,
               "window_d": 8, "dt_factor": 0.3, "density_scale": 1000, "target_cv": None, "steady_min_d": None}
OLD_SETTLE = {"cloud_fraction": 0.25, "relax_time_factor": 1.5}
FIDELITY_POINTS = ["normal", "narrow_gap_large", "small_diameter", "low_friction_fast"]
# the precision arm as it was benchmarked (commit 65b543f^): the window opened once the flow was
# steady (1 d beyond the pile at the earliest), lasted at least 4 d, and c was the flat floor's 0.45
PRECISION_0 = {"presets": {"default": {"steady_min_d": 1, "window_d": 4}}, "metrics": {"counting_noise_c": 0.45}}
ARMS = {
    "today": {"rev": "2e05ec5", "overrides": {}},
    "physics": {"rev": None, "overrides": {"presets": {"default": OLD_DEFAULT}, "scene": OLD_SETTLE}},
    "precision": {"rev": None, "overrides": PRECISION_0},
    # the same-seed check that the cheaper settle and relax move neither MFR nor PD beyond the noise
    "precision_slow_settle": {"rev": None, "overrides": {**PRECISION_0, "scene": OLD_SETTLE},
                              "points": FIDELITY_POINTS},
    # the window opens 3 d beyond the pile, lasts at least 8 d and until (c / target_cv)^2 spheres
    # have passed, c calibrated on the rough substrate; the pile without its standing reserve (run
    # 2026-12-01: it ran down at h/d >= 3)
    "window8": {"rev": None, "overrides": {"scene": {"pile_reserve": 0.0}}},
    # this tree as shipped: window8 with the pile's standing reserve (scene.pile_reserve)
    "shipped": {"rev": None, "overrides": {}},
    # the pile's standing reserve tried at the corner, where window8's pile ran down: a heap h and
    # 2 h long there (pile_reserve x h^2 / (h + heap)); the shipped 4.7 is the 2 h heap
    # the deposit frozen 8 d behind the blade once at rest, the substrate behind it removed
    # (scene.freeze_behind_d; issue 31)
    "freeze": {"rev": None, "overrides": {"scene": {"freeze_behind_d": 8}}},
    # the heap left to come to rest before the blade starts: relax up to 2 free-fall times of the
    # pile instead of 0.5 (it ended on its time cap with spheres at up to 44 mm/s)
    "rested": {"rev": None, "overrides": {"scene": {"relax_time_factor": 2.0}}},
    # the heap fed from above during the move (scene.fed_heap; issue 31): the pile holds what
    # passes before the window plus the standing reserve, spheres are added ahead of the blade
    # whenever the heap falls below that reserve; the window's length no longer sizes the pile
    "fed": {"rev": None, "overrides": {"scene": {"fed_heap": True}}},
    # its first variant (commit 76258bb): one drop height over the zone at the blade's front face,
    # 1.5 d above the highest sphere there
    "fed_v1": {"rev": "76258bb", "overrides": {"scene": {"fed_heap": True}}},
    # the same, the spheres dropped 3-7 d ahead of the blade's front face (on the heap's slope,
    # where a long pile's powder joins the heap) instead of at it
    "fed_ahead": {"rev": None, "overrides": {"scene": {"fed_heap": True, "feed_offset_d": 3}}},
    # the feed as first shipped (commit 480549f): at most two layers a call, the next once they
    # have fallen (it fell behind at the corner); `fed` is the shipped config's feed
    "fed_v2": {"rev": "480549f", "overrides": {"scene": {"fed_heap": True, "feed_offset_d": 3}}},
    # the fed heap with twice the standing reserve, at the corner: is 4.7 h^2 enough there?
    "fed_2x": {"rev": None, "overrides": {"scene": {"fed_heap": True, "pile_reserve": 9.4}},
               "points": ["fine_thick_corner"]},
    # the fed heap with half the standing reserve, at the corner: does MFR hold with a heap half
    # the size (and half the corner's spheres)?
    "fed_half": {"rev": None, "overrides": {"scene": {"fed_heap": True, "pile_reserve": 2.35}},
                 "points": ["fine_thick_corner"]},
    # the study's flat floor with the fed heap (shipped) and with the full pile (before it): does a
    # fed heap keep the flat floor's pile from draining at thin gaps? (issue 36)
    "flat_fed": {"rev": None, "overrides": {"scene": {"substrate": {"kind": "flat"}}},
                 "points": [*FLOOR_POINTS, "narrow_gap_large"]},
    "flat_full": {"rev": None, "overrides": {"scene": {"substrate": {"kind": "flat"}, "fed_heap": False}},
                  "points": [*FLOOR_POINTS, "narrow_gap_large"]},
    # the bed's width (periodic across), the knob the fidelity study never ran at 16 d: the shipped
    # 10 d against 5 d and 16 d at the default preset (issue 32)
    "width_5": {"rev": None, "overrides": {"presets": {"default": {"width_d": 5}}}, "points": ["normal", "narrow_gap_large"]},
    "width_16": {"rev": None, "overrides": {"presets": {"default": {"width_d": 16}}}, "points": ["normal", "narrow_gap_large"]},
    "reserve_1h": {"rev": None, "overrides": {"scene": {"pile_reserve": 2.33}}, "points": ["fine_thick_corner"]},
    "reserve_2h": {"rev": None, "overrides": {"scene": {"pile_reserve": 4.67}}, "points": ["fine_thick_corner"]},
    # the scene before sphere-box contacts (floor, walls, blade) were read every overlap_every steps
    # like sphere-sphere ones (issue 32; every 1000 steps before): what the finer check costs; the
    # check only reads, so MFR and PD must come out bit for bit the same
    "before_box_check": {"rev": "db1422d", "overrides": {}},
    # the scene issue 31 measured (the last tree before the frozen deposit shipped): the standing
    # reserve in a full pile, no freeze, no feed, box contacts read every 1000 steps; the arm the
    # issue's goal is stated against
    "issue31_start": {"rev": "dd28def", "overrides": {}},
    # issue 50's steady window and its cost lever (docs/steady_window): the window opened 5 d beyond
    # the pile (steady, 1.28x the CPU in a main job); the fed heap feeding the transient's passing
    # instead of piling it (scene.feed_transient), at the shipped 3 d and with the 5 d window
    "window5": {"rev": None, "overrides": {"presets": {"default": {"transient_d": 5}}}},
    "fed_transient": {"rev": None, "overrides": {"scene": {"feed_transient": True}}},
    "window5_fed_transient": {"rev": None, "overrides": {"presets": {"default": {"transient_d": 5}},
                                                         "scene": {"feed_transient": True}}},
    # the window opened 5 d beyond the pile with the pile sized for 3 d as shipped
    # (presets.default.pile_transient_d): the shipped run's pile, settle and feed, measured 2 d later
    "window5_pile3": {"rev": None, "overrides": {"presets": {"default": {"transient_d": 5, "pile_transient_d": 3}}}},
    # the peak overlap read twice per shortest contact instead of four times (every 4 steps at
    # `default` instead of 2; the check's sampling factor ~1.37 instead of 1.05-1.09): it only reads,
    # so MFR and PD must come out bit for bit the same (issue 50's overlap lever, a step further)
    "reads2": {"rev": None, "overrides": {"presets": {"default": {"overlap_reads_per_contact": 2}}}},
}
CASE_COLUMNS = ["n_particles", "steps", "mfr", "pd", "n_passed", "mfr_sd", "pd_sd", "mfr_sd_within", "layer_fill",
                "coverage", "roughness_d", "thickness_ratio", "regime", "peak_overlap_ratio", "peak_overlap_settle",
                "peak_overlap_relax", "peak_overlap_move", "rolled_off_particles", "flow_trend", "flow_trend_z", "flagged",
                "peak_overlap_free", "peak_overlap_wedged", "wedged",
                # the heap ahead of the blade at the window's start and end, in h^2 (empty in older rows)
                "heap_start_h2", "heap_end_h2"]
CSV_COLUMNS = ["arm", "point", "seed", "f", "d_um", "h_um", "v_mm_s", "status", "cpu_time", "wall_time",
               *CASE_COLUMNS, "case_dir"]

RENDER = r"""
import json, sys
from spreadmap import config as cfgmod
try:
    from spreadmap.case.identity import rounded
    from spreadmap.case.render import render, template_sha256
    from spreadmap.case.scene import scene_parameters
except ImportError:  # an arm's older tree (`rev`), from before spreadmap/case/ (issue 34)
    from spreadmap.cases import rounded
    from spreadmap.render import render, template_sha256
    from spreadmap.scene import scene_parameters
job = json.loads(sys.argv[1])
cfg = cfgmod.load(job["config"])
def update(base, new):
    for k, v in new.items():
        if isinstance(v, dict) and isinstance(base.get(k), dict):
            update(base[k], v)
        else:
            base[k] = v
update(cfg, job["overrides"])
point = dict(zip(("f", "d_um", "h_um", "v_mm_s"), job["point"]))
params = {**scene_parameters(rounded(point), "default", cfg, job["case_id"], job["seed"]), "scene_sha256": template_sha256()}
params["preset"] = "default"
open(job["script"], "w").write(render(params))
json.dump(params, open(job["params"], "w"))
"""


def tree_of(rev: str | None, base: Path) -> Path:
    """This tree, or revision `rev` of this repository extracted under `base`."""
    if rev is None:
        return ROOT
    out = base / f"tree-{rev}"
    if not out.exists():
        out.mkdir(parents=True)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "spreadmap", "yade_scripts", "schemas",
                                  "config.yaml"], check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(out)], input=archive, check=True)
    return out


def build_jobs(arms: list[str], points: list[str], seeds: list[int], base: Path) -> list[dict]:
    jobs = []
    for name in points:
        for seed in seeds:
            for arm in arms:
                if name not in ARMS[arm].get("points", POINTS):
                    continue
                tree = tree_of(ARMS[arm]["rev"], base)
                case_dir = base / "cases" / f"{arm}-{name}-s{seed}"
                jobs.append({"arm": arm, "point_name": name, "point": POINTS[name], "seed": seed, "tree": str(tree),
                             "config": str(tree / "config.yaml"), "overrides": ARMS[arm]["overrides"],
                             "case_id": f"{arm}-{name}-s{seed}", "case_dir": str(case_dir),
                             "script": str(case_dir / "case.py"), "params": str(case_dir / "params.json")})
    return jobs


def run_job(job: dict) -> dict:
    from spreadmap.case.launcher import run_case

    case_dir = Path(job["case_dir"])
    case_dir.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHONPATH": job["tree"]}
    subprocess.run([sys.executable, "-c", RENDER, json.dumps(job)], env=env, check=True, cwd=job["tree"])
    params = json.loads(Path(job["params"]).read_text())
    raw_path = case_dir / "raw.json"
    raw_path.unlink(missing_ok=True)
    # a generous outer limit: a benchmark on a busy machine must not lose its slowest cases
    result = run_case(job["script"], raw_path, case_dir / "run.log", 4.0 * params["timeout_s"])
    (case_dir / "result.json").write_text(json.dumps(result))
    (case_dir / "arm.json").write_text(json.dumps(arm_identity(job)))
    return result


def arm_identity(job: dict) -> dict:
    """What makes a kept case this job's: its arm's definition, point and seed. A kept case
    directory is re-used only when its arm.json equals this (an arm renamed or redefined since, or
    a directory from before arm.json, is run again rather than read under the wrong name)."""
    return {"arm": job["arm"], "rev": ARMS[job["arm"]]["rev"], "overrides": job["overrides"],
            "point": list(job["point"]), "seed": job["seed"]}


def kept(job: dict) -> bool:
    case_dir = Path(job["case_dir"])
    if not (case_dir / "result.json").exists() or not (case_dir / "arm.json").exists():
        return False
    return json.loads((case_dir / "arm.json").read_text()) == json.loads(json.dumps(arm_identity(job)))


def case_row(job: dict, config: dict) -> dict:
    """One row from a case directory's raw result, with this tree's metrics."""
    from spreadmap.metrics import case_metrics

    case_dir = Path(job["case_dir"])
    row = {"arm": job["arm"], "point": job["point_name"], "seed": job["seed"],
           **dict(zip(("f", "d_um", "h_um", "v_mm_s"), job["point"])), "case_dir": str(case_dir)}
    result = json.loads((case_dir / "result.json").read_text()) if (case_dir / "result.json").exists() else {}
    raw_path = case_dir / "raw.json"
    row.update(status=result.get("outcome", "missing"), cpu_time=result.get("cpu_time", math.nan),
               wall_time=result.get("wall_time", math.nan))
    if raw_path.exists():
        raw = json.loads(raw_path.read_text())
        raw["params"].setdefault("point", dict(zip(("f", "d_um", "h_um", "v_mm_s"), job["point"])))
        recount_escaped(raw)
        # the PD box's clearance must fit every arm's window (today's: 8 d, a 2 d blade)
        m = case_metrics({**raw, "cpu_time": row["cpu_time"]}, config["regime"], config["stability"], config["metrics"])
        for key in CASE_COLUMNS:
            row[key] = m.get(key, math.nan)
    return row


def recount_escaped(raw: dict) -> None:
    """Spheres through a side wall or the floor at the run's end (the window_end snapshot), against
    the floor's real top (geometry.floor_top: -d under a rough substrate). The scene's own count
    used z = 0 until commit 54bad9d and so counted the spheres that rolled beyond the substrate's
    end onto the floor below it, which flagged most rough-substrate cases of this run."""
    geometry = raw.get("geometry") or {}
    end = (raw.get("snapshots") or {}).get("window_end")
    if "floor_top" not in geometry or not end:
        return
    pos, r = np.asarray(end["positions"], float), np.asarray(end["radii"], float)
    x_lo, x_hi = geometry["floor_x"]
    on_floor = (pos[:, 0] >= x_lo) & (pos[:, 0] <= x_hi)
    inside = ((pos[:, 1] >= -r) & (pos[:, 1] <= geometry["width"] + r) & (pos[:, 2] >= geometry["floor_top"] - r))
    # and thrown far upwards, as the scene counts it (above cloud height + 40 d): without this the
    # first fed heap's corner case, a 297 d tower with 1,068 spheres above the box, read 0 escaped
    params = raw.get("params") or {}
    if "cloud_height" in params and "diameter" in params:
        inside &= pos[:, 2] <= params["cloud_height"] + 40.0 * params["diameter"]
    raw["escaped_particles"] = int(np.sum(on_floor & ~inside))


def information(rows: list[dict], target: str) -> dict:
    """Per point: mean, seed SD, CV, mean CPU, information per CPU-second."""
    values = np.array([r[target] for r in rows], float)
    cpu = np.array([r["cpu_time"] for r in rows], float)
    mean, sd = values.mean(), values.std(ddof=1)
    cv = sd / mean
    return {"n": len(rows), "mean": mean, "sd": sd, "cv": cv, "cpu": cpu.mean(), "info": 1.0 / (cv ** 2 * cpu.mean()),
            "recorded_sd": np.nanmean([r.get(f"{target}_sd", math.nan) for r in rows]),
            "n_passed": np.nanmean([r.get("n_passed", math.nan) for r in rows])}


def bootstrap_ratio(by_point: dict, arm: str, target: str, n_boot: int = 2000, seed: int = 0):
    """Mean over points of info(arm) / info(today), with a 95 % interval from resampling seeds
    within each point and arm."""
    rng = np.random.default_rng(seed)
    points = sorted(by_point)

    def ratio(sample):
        out = []
        for p in points:
            a, t = sample(by_point[p][arm]), sample(by_point[p]["today"])
            out.append(information(a, target)["info"] / information(t, target)["info"])
        return float(np.mean(out)), out

    point_estimate, per_point = ratio(lambda rows: rows)
    boots = []
    for _ in range(n_boot):
        def sample(rows):
            picks = [rows[i] for i in rng.integers(0, len(rows), len(rows))]
            vals = [r[target] for r in picks]
            return picks if np.std(vals) > 0 else rows  # a degenerate draw (all one case) has no CV
        boots.append(ratio(sample)[0])
    lo, hi = np.percentile(boots, [2.5, 97.5])
    return point_estimate, lo, hi, dict(zip(points, per_point))


def pooled_constant(by_point: dict, arm: str, target: str) -> float:
    """The arm's counting-noise constant c, pooled over points: CV^2 = c^2 / N at each point, so
    c^2 = sum (n - 1) CV^2 N / sum (n - 1) over points (n seeds, N spheres passed, CV the seed CV)."""
    num = den = 0.0
    for arms in by_point.values():
        rows = arms.get(arm, [])
        if len(rows) < 2:
            continue
        s = information(rows, target)
        num += (s["n"] - 1) * s["cv"] ** 2 * s["n_passed"]
        den += s["n"] - 1
    return math.sqrt(num / den) if den else math.nan


def pooled_ratio(by_point: dict, arm: str, target: str, n_boot: int = 2000, seed: int = 0):
    """Information per CPU-second of `arm` over `today`'s, mean over points, with the seed CV of
    each arm modelled as c_arm / sqrt(N) (c pooled over the points, far steadier than a 4-seed CV
    at each point): ratio_p = (N_arm / CPU_arm) / (N_today / CPU_today) x (c_today / c_arm)^2.
    95 % interval from resampling seeds within each point and arm."""
    rng = np.random.default_rng(seed)
    points = sorted(p for p in by_point if arm in by_point[p] and "today" in by_point[p])

    def estimate(data):
        c_arm, c_today = pooled_constant(data, arm, target), pooled_constant(data, "today", target)
        per = {}
        for p in points:
            a, t = information(data[p][arm], target), information(data[p]["today"], target)
            per[p] = (a["n_passed"] / a["cpu"]) / (t["n_passed"] / t["cpu"]) * (c_today / c_arm) ** 2
        return float(np.mean(list(per.values()))), per, c_arm, c_today

    est, per, c_arm, c_today = estimate(by_point)
    boots = []
    for _ in range(n_boot):
        data = {p: {a: [rows[i] for i in rng.integers(0, len(rows), len(rows))] for a, rows in by_point[p].items()}
                for p in points}
        try:
            value = estimate(data)[0]
        except ZeroDivisionError:  # a draw of one case repeated has no spread
            continue
        if math.isfinite(value):
            boots.append(value)
    lo, hi = np.percentile(boots, [2.5, 97.5])
    return est, lo, hi, per, c_arm, c_today


def recorded_against_seed(cells: dict, arm: str, target: str, level: float = 0.95):
    """The case's recorded noise SD against the seed-to-seed SD, pooled over points: if each
    point's seed variance is k x its recorded variance, sum (n-1) s^2 / r^2 ~ k chi^2(dof), so
    recorded / seed = 1 / sqrt(k) with a chi-square interval (a 4-seed SD alone is uncertain by
    -40 %/+90 % at 95 %, which the per-point column shows). Returns (ratio, lo, hi, dof)."""
    from scipy import stats

    num, dof = 0.0, 0
    for d in cells.values():
        rows = d.get(arm, [])
        if len(rows) < 2:
            continue
        s = information(rows, target)
        if not (math.isfinite(s["recorded_sd"]) and s["recorded_sd"] > 0):
            continue
        num += (s["n"] - 1) * (s["sd"] / s["recorded_sd"]) ** 2
        dof += s["n"] - 1
    if not dof:
        return math.nan, math.nan, math.nan, 0
    k = num / dof
    k_lo, k_hi = num / stats.chi2.ppf((1 + level) / 2, dof), num / stats.chi2.ppf((1 - level) / 2, dof)
    return 1 / math.sqrt(k), 1 / math.sqrt(k_hi), 1 / math.sqrt(k_lo), dof


def paired_shift(arm_rows: list[dict], base_rows: list[dict], target: str) -> dict:
    """An arm against `shipped` at one point, seed by seed (same packing seeds): the mean
    difference, its standard error from the paired differences' spread (n - 1 dof) and z."""
    base = {r["seed"]: r[target] for r in base_rows}
    diffs = np.array([r[target] - base[r["seed"]] for r in arm_rows if r["seed"] in base])
    n = len(diffs)
    if n < 2:
        return {"n": n, "diff": math.nan, "se": math.nan, "z": math.nan}
    mean_base = np.mean([base[r["seed"]] for r in arm_rows if r["seed"] in base])
    se = float(diffs.std(ddof=1) / math.sqrt(n))
    return {"n": n, "diff": float(diffs.mean()), "rel": float(diffs.mean() / mean_base), "se": se,
            "z": float(diffs.mean() / se) if se > 0 else math.nan}


def against_shipped(by_point: dict, arms: list[str]) -> list[str]:
    """Each arm against `shipped`, same seeds: per point the paired shift of MFR and PD with its
    SE, the chi-square of the points' z (k dof: is any shift there at all?) and the CPU ratio
    (ratio of the points' mean CPU, with a 95 % interval from resampling seeds within points)."""
    from scipy import stats

    lines = ["## Against shipped, same seeds", ""]
    for a in arms:
        points = sorted(p for p, d in by_point.items() if a in d and "shipped" in d)
        if not points:
            continue
        lines += [f"### {a}", "", "| point | seeds | MFR shift (SE) | t | PD shift (SE) | t | CPU s arm / shipped | ratio |",
                  "|---|---|---|---|---|---|---|---|"]
        chi = {"mfr": [], "pd": []}
        for p in points:
            m, q = (paired_shift(by_point[p][a], by_point[p]["shipped"], t) for t in target_names("base"))
            for t, r in (("mfr", m), ("pd", q)):
                if math.isfinite(r["z"]):  # t with n - 1 dof, as the normal z of the same tail probability
                    chi[t].append(float(stats.norm.isf(stats.t.sf(abs(r["z"]), r["n"] - 1))) ** 2)
            ca, cs = (np.mean([r["cpu_time"] for r in by_point[p][x]]) for x in (a, "shipped"))
            lines.append(f"| {p} | {m['n']} | {m['diff']:+.4f} ({m['se']:.4f}) | {m['z']:+.1f} | "
                         f"{q['diff']:+.4f} ({q['se']:.4f}) | {q['z']:+.1f} | {ca:.1f} / {cs:.1f} | {ca / cs:.2f} |")
        rng = np.random.default_rng(0)
        boot = []
        for _ in range(2000):
            ta = sum(np.mean(rng.choice([r["cpu_time"] for r in by_point[p][a]], len(by_point[p][a]))) for p in points)
            ts = sum(np.mean(rng.choice([r["cpu_time"] for r in by_point[p]["shipped"]], len(by_point[p]["shipped"])))
                     for p in points)
            boot.append(ta / ts)
        total_a = sum(np.mean([r["cpu_time"] for r in by_point[p][a]]) for p in points)
        total_s = sum(np.mean([r["cpu_time"] for r in by_point[p]["shipped"]]) for p in points)
        lo, hi = np.percentile(boot, [2.5, 97.5])
        lines.append("")
        for t in target_names("base"):
            k = len(chi[t])
            if k:
                lines.append(f"- **{a}, {t.upper()}**: chi-square over the {k} points = {sum(chi[t]):.1f} ({k} dof, "
                             f"p = {stats.chi2.sf(sum(chi[t]), k):.3f}; each point's paired t taken as the normal z "
                             f"of the same tail probability)")
        lines.append(f"- **{a}, CPU**: the points' mean CPU summed, arm / shipped = {total_a / total_s:.2f} "
                     f"(95 % interval from resampling seeds {lo:.2f}-{hi:.2f})")
        lines.append("")
    return lines


def report(rows: list[dict], arms: list[str]) -> str:
    ok = [r for r in rows if r["status"] == "ok" and math.isfinite(r.get("mfr", math.nan))]
    by_point: dict = {}
    for r in ok:
        by_point.setdefault(r["point"], {}).setdefault(r["arm"], []).append(r)
    # each arm at the points where it has >= 2 seeds beside today's (an arm not run at a point, or
    # not yet, is left out there and its ratios are over the other points)
    complete = {p: {a: r for a, r in d.items() if len(r) >= 2} for p, d in by_point.items()}
    complete = {p: d for p, d in complete.items() if "today" in d or "today" not in arms}
    per_arm = ", ".join(f"{a} {sum(a in d for d in complete.values())}" for a in arms)
    lines = [f"# Information per CPU-second: {', '.join(arms)}", "",
             f"{len(ok)} of {len(rows)} cases ok; points per arm: {per_arm}.", ""]
    lines += ["## Spheres measured per CPU-second (the information per CPU-second if c is the same in every arm)", "",
              "| point | " + " | ".join(arms) + " |", "|---|" + "---|" * len(arms)]
    ratios: dict = {a: [] for a in arms}
    for p in sorted(complete):
        cells = []
        for a in arms:
            rows_a = complete[p].get(a, [])
            if not rows_a:
                cells.append("-")
                continue
            rate = np.mean([r["n_passed"] for r in rows_a]) / np.mean([r["cpu_time"] for r in rows_a])
            today = complete[p].get("today", [])
            base = (np.mean([r["n_passed"] for r in today]) / np.mean([r["cpu_time"] for r in today])) if today else math.nan
            if math.isfinite(base):
                ratios[a].append(rate / base)
                cells.append(f"{rate:.2f} ({rate / base:.2f}x)")
            else:  # no `today` arm in this run: the rate alone
                cells.append(f"{rate:.2f}")
        lines.append(f"| {p} | " + " | ".join(cells) + " |")
    lines += [""] + [f"- **{a}**: {np.mean(ratios[a]):.2f}x today's spheres per CPU-second, mean over "
                     f"{len(ratios[a])} points (range {min(ratios[a]):.2f}-{max(ratios[a]):.2f})"
                     for a in arms if a != "today" and ratios[a]] + [""]
    for target in target_names("base"):
        lines += [f"## {target.upper()}", "",
                  "| point | arm | seeds | mean | seed SD | CV | recorded SD / seed SD | N passed | CPU s | info / CPU s |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for p in sorted(complete):
            for a in arms:
                if a not in complete[p]:
                    continue
                s = information(complete[p][a], target)
                rec = s["recorded_sd"] / s["sd"] if math.isfinite(s["recorded_sd"]) else math.nan
                lines.append(f"| {p} | {a} | {s['n']} | {s['mean']:.4f} | {s['sd']:.4f} | {s['cv']:.3f} | "
                             f"{rec:.2f} | {s['n_passed']:.0f} | {s['cpu']:.1f} | {s['info']:.3g} |")
        lines += [""]
        for a in arms:
            ratio, lo, hi, dof = recorded_against_seed(complete, a, target)
            if dof:
                lines.append(f"- **{a}, {target.upper()}**: recorded noise SD / seed SD pooled over points "
                             f"{ratio:.2f} (95 % interval {lo:.2f}-{hi:.2f}, {dof} dof)")
        lines += [""]
        for a in arms:
            if a == "today" or "today" not in arms:
                continue
            with_arm = {p: d for p, d in complete.items() if a in d}
            if not with_arm:
                continue
            est, lo, hi, per = bootstrap_ratio(with_arm, a, target)
            lines.append(f"- **{a} / today, {target.upper()}**, each point's own seed CV: mean over points "
                         f"{est:.2f}x (95 % bootstrap interval {lo:.2f}-{hi:.2f}); per point: "
                         + ", ".join(f"{p} {v:.2f}" for p, v in sorted(per.items())))
            est, lo, hi, per, c_arm, c_today = pooled_ratio(with_arm, a, target)
            lines.append(f"- **{a} / today, {target.upper()}**, CV = c / sqrt(N) with c pooled over points "
                         f"(c = {c_arm:.3f} against today's {c_today:.3f}): mean over points {est:.2f}x "
                         f"(95 % bootstrap interval {lo:.2f}-{hi:.2f}); per point: "
                         + ", ".join(f"{p} {v:.2f}" for p, v in sorted(per.items())))
        lines += [""]
    if "precision_slow_settle" in arms and "precision" in arms:
        lines += ["## The cheaper settle and relax, same seeds (precision against precision_slow_settle)", "",
                  "| point | target | cheaper | old settle | difference | SE of the difference | CPU ratio |",
                  "|---|---|---|---|---|---|---|"]
        for p in sorted(complete):
            a, b = complete[p].get("precision", []), complete[p].get("precision_slow_settle", [])
            if len(a) < 2 or len(b) < 2:
                continue
            for target in target_names("base"):
                va, vb = np.array([r[target] for r in a]), np.array([r[target] for r in b])
                se = math.sqrt(va.var(ddof=1) / len(va) + vb.var(ddof=1) / len(vb))
                cpu_ratio = np.mean([r["cpu_time"] for r in a]) / np.mean([r["cpu_time"] for r in b])
                lines.append(f"| {p} | {target.upper()} | {va.mean():.4f} | {vb.mean():.4f} | "
                             f"{va.mean() - vb.mean():+.4f} | {se:.4f} | {cpu_ratio:.2f} |")
        lines += [""]
    if "shipped" in arms:
        lines += against_shipped(by_point, [a for a in arms if a not in ("shipped", "today")])
    cpu = {a: [r["cpu_time"] for r in ok if r["arm"] == a] for a in arms}
    lines += ["## CPU per case", "", "| arm | cases | median CPU s | max CPU s | total CPU h |", "|---|---|---|---|---|"]
    for a in arms:
        if cpu[a]:
            lines.append(f"| {a} | {len(cpu[a])} | {np.median(cpu[a]):.1f} | {max(cpu[a]):.1f} | {sum(cpu[a]) / 3600:.2f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--arms", nargs="+", default=list(ARMS), choices=list(ARMS))
    ap.add_argument("--points", nargs="+", default=DEFAULT_POINTS, choices=list(POINTS))
    ap.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3, 4])
    ap.add_argument("--today-rev", default=ARMS["today"]["rev"], help="revision of the `today` arm")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--keep", help="directory for the cases (default: a temporary one, removed)")
    ap.add_argument("--recompute", help="a kept directory: recompute the tables from its raw results, run nothing")
    ap.add_argument("--csv", help="one row per case")
    ap.add_argument("--resume-csv", help="a published cases CSV of an earlier run: its ok rows are taken as they are "
                    "and their cases not run again (the next session resumes where this one stopped)")
    ap.add_argument("--summary", help="the Markdown summary")
    args = ap.parse_args(argv)
    ARMS["today"]["rev"] = args.today_rev
    from spreadmap import config as cfgmod
    from spreadmap.host import description_lines

    config = cfgmod.load(ROOT / "config.yaml")
    print("\n".join(description_lines()), flush=True)
    tmp = None
    if args.recompute:
        base = Path(args.recompute).resolve()
    elif args.keep:
        base = Path(args.keep).resolve()
        base.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="spreadmap-precision-")
        base = Path(tmp.name)
    jobs = build_jobs(args.arms, args.points, args.seeds, base)
    published = {}
    if args.resume_csv and Path(args.resume_csv).exists():
        # a published CSV (docs/precision) is checked against its folder's SHA256SUMS first
        resumed = verified_bytes(args.resume_csv, required=False).decode()
        with io.StringIO(resumed, newline="") as fh:
            for r in csv.DictReader(fh):
                if r["status"] == "ok":
                    published[(r["arm"], r["point"], int(r["seed"]))] = {  # a column's old name read as its name now
                        current_name(k): (r[k] if k in ("arm", "point", "status", "regime", "case_dir") else
                            (r[k] == "True") if k in ("flagged", "wedged") else float(r[k]) if r[k] != "" else math.nan)
                        for k in r}
        print(f"{len(published)} finished cases taken from {args.resume_csv}", flush=True)
    jobs_to_run = [j for j in jobs if (j["arm"], j["point_name"], j["seed"]) not in published]
    if not args.recompute:
        print(f"{len(jobs)} cases: {len(args.points)} points x seeds {args.seeds} x arms {args.arms}, interleaved; "
              f"{args.workers} YADE processes at once, in {base}", flush=True)
        start = time.perf_counter()
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=args.workers, mp_context=context) as pool:
            futures = {pool.submit(run_job, job): job for job in jobs_to_run if not kept(job)}  # a kept run resumes
            for done, future in enumerate(as_completed(futures), 1):
                job = futures[future]
                try:
                    result = future.result()
                    print(f"[{done}/{len(futures)}] {job['case_id']}: {result.get('outcome')}, cpu "
                          f"{result.get('cpu_time', math.nan):.1f} s", flush=True)
                except Exception as error:
                    print(f"[{done}/{len(futures)}] {job['case_id']}: launcher error {error}", flush=True)
        print(f"ran in {time.perf_counter() - start:.0f} s wall", flush=True)
    rows = [published.get((job["arm"], job["point_name"], job["seed"])) or case_row(job, config) for job in jobs]
    for r in rows:
        r["seed"] = int(r["seed"])
    text = report(rows, args.arms)
    print(text)
    if args.csv:
        write_csv_atomically(args.csv, [{**r, "case_dir": Path(r["case_dir"]).name} for r in rows], CSV_COLUMNS)
        if republish_if_listed(args.csv):  # a published table: its folder's checksums follow it
            print(f"re-published the checksums of {args.csv}", flush=True)
    if args.summary:
        Path(args.summary).parent.mkdir(parents=True, exist_ok=True)
        Path(args.summary).write_text(text)
    if tmp is not None:
        tmp.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
