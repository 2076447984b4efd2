#!/usr/bin/env python
"""Does the answer depend on how much powder stands ahead of the blade? MFR and PD against the fed
heap's size, on both floors, at a thin and a wide gap (issue 50).

The fed heap (scene.fed_heap, shipped) holds `scene.pile_reserve` x h^2 of bulk powder ahead of the
blade's rear face (plus what fills the gap under the blade): the scene feeds spheres onto its slope
whenever it falls below that. Arms: the reserve at 1.5, 3, 4.7 (shipped) and 9.4 h^2, on the rough
floor (shipped) and the study's flat floor; everything else as shipped (`default` preset, adhesion
on). Points:
  thin   f 0.30, d 40 um, h 60 um, v 10 mm/s (h/d 1.5)
  wide   f 0.30, d 20 um, h 70 um, v 10 mm/s (h/d 3.5)
  corner f 0.30, d 12 um, h 70 um, v 10 mm/s (h/d 5.8: the costliest corner of the main job, where the
         heap's h^2 is most of the spheres; run with --points corner, rough floor, two reserves)
Each case runs in its own YADE process, two at a time, lowest seed first (a run cut short keeps
balanced arms), every finished case appended to --csv at once (spreadlab.experiments.arms).

    .venv/bin/python benchmarks/heap_size.py --seeds 1 2 3 --csv docs/heap_size/cases.csv \
        --summary docs/heap_size/summary.md --keep /tmp/heap_size
    .venv/bin/python benchmarks/heap_size.py --plan     # spheres and modelled CPU of each case, no run
"""
from __future__ import annotations

import argparse
import copy
import sys
from pathlib import Path

import numpy as np

from spreadlab.experiments.arms import add_arguments, arm_summary, number, pending, read_rows, run_arm_case, run_jobs, usable
from spreadmap import config as spreadmap_config
from spreadmap.case.scene import scene_parameters, standing_reserve_h2
from spreadmap.files import write_text_atomically
from spreadmap.loop.cost import PlannedCost
from spreadmap.targets import names as target_names

ROOT = Path(__file__).resolve().parent.parent
POINTS = {"thin": (0.30, 40.0, 60.0, 10.0), "wide": (0.30, 20.0, 70.0, 10.0), "corner": (0.30, 12.0, 70.0, 10.0),
          # 2026-12-07: two points the sweep had not seen, for the reserve in d^2 (arm rough_d40)
          "mid": (0.30, 16.0, 69.0, 10.0), "mid_f45": (0.45, 14.0, 70.0, 10.0),
          # the main job's LDS point where 40 d^2 read MFR 0.244 and 4.7 h^2 0.392 (seed 1, 2026-12-07)
          "low_f": (0.1607, 12.12, 62.494, 12.7047),
          "mid_f16": (0.16, 16.0, 69.0, 10.0),  # mid at low friction
          # 2026-12-07 (session 30): the d^2 heap from f 0.30 only, checked at the friction bound's edge
          "corner_f31": (0.31, 11.0, 72.0, 12.0)}
RESERVES = (1.5, 3.0, 4.7, 9.4)
# arm -> (floor, reserve [h^2, the most], reserve [d^2] or None: scene.pile_reserve_d2)
ARMS = {f"{floor}_r{r:g}": (floor, r, None) for floor in ("rough", "flat") for r in RESERVES}
ARMS["rough_d40"] = ("rough", 4.7, 40.0)  # 40 d^2, between 1.5 and 4.7 h^2
REFERENCE_ARM = "rough_r4.7"
COLUMNS = ("arm", "floor", "pile_reserve", "point", "seed", "case_id", "f", "d_um", "h_um", "v_mm_s", "status",
           "flagged", "flag_reason", "regime", "mfr", "pd", "mfr_sd", "pd_sd", "n_passed", "coverage",
           "thickness_ratio", "flow_trend", "flow_trend_z", "heap_start_h2", "heap_end_h2", "bond_number",
           "n_particles", "fed_particles", "rolled_off_particles", "steps", "peak_overlap_free",
           "peak_overlap_wedged", "cpu_time", "wall_time")


def arm_config(base: dict, arm: str) -> dict:
    """The config of an arm: the shipped one with its floor and heap reserve set (a d^2 arm holds its
    d^2 heap at every friction, scene.pile_reserve_d2_from_f 0, as it ran before that key)."""
    floor, reserve, per_d2 = ARMS[arm]
    cfg = copy.deepcopy(base)
    cfg["scene"]["substrate"]["kind"] = floor
    cfg["scene"]["pile_reserve"] = reserve
    cfg["scene"]["pile_reserve_d2"] = per_d2
    cfg["scene"]["pile_reserve_d2_from_f"] = 0.0
    return cfg


def point_dict(name: str) -> dict:
    f, d, h, v = POINTS[name]
    return {"f": f, "d_um": d, "h_um": h, "v_mm_s": v}


def run_one(job: dict) -> dict:
    cfg = arm_config(job["base"], job["arm"])
    row, params = run_arm_case(cfg, "default", point_dict(job["point"]), job["seed"], job["keep"], COLUMNS)
    f, d, h, _ = POINTS[job["point"]]
    row.update({"arm": job["arm"], "point": job["point"], "floor": ARMS[job["arm"]][0],
                "pile_reserve": round(standing_reserve_h2(cfg["scene"], d, h, f), 4)})  # the reserve it ran [h^2]
    return row


def plan(base: dict) -> None:
    """Spheres, feed count and modelled CPU seconds of each arm's case at each point."""
    for point in POINTS:
        for arm in ARMS:
            cfg = arm_config(base, arm)
            params = scene_parameters(point_dict(point), "default", cfg, "plan")
            cpu = PlannedCost(cfg, "default")(np.array([POINTS[point]]))[0]
            print(f"{point:5s} {arm:12s} spheres {params['n_particles']:5d} heap {params['feed_count']:5d} "
                  f"steps {params['estimated_steps']:7d} modelled CPU {cpu:6.0f} s")


def trend_lines(rows: list[dict]) -> str:
    """Per point and floor: the least-squares slope of MFR and PD against log2 of the reserve (per
    doubling of the heap) over every usable case, with its SE from the residuals."""
    good = usable(rows)
    out = ["", "| point | floor | cases | MFR per doubling of the heap (SE) | PD per doubling (SE) |", "|---|---|---|---|---|"]
    for point in POINTS:
        for floor in ("rough", "flat"):
            group = [r for r in good if r["point"] == point and r["floor"] == floor]
            if len(group) < 3:
                continue
            x = np.log2([number(r["pile_reserve"]) for r in group])
            cells = []
            for key in target_names("base"):
                y = np.array([number(r[key]) for r in group])
                design = np.column_stack([np.ones_like(x), x])
                coef, *_ = np.linalg.lstsq(design, y, rcond=None)
                resid = y - design @ coef
                dof = len(y) - 2
                cov = np.linalg.inv(design.T @ design) * (resid @ resid / dof if dof > 0 else np.nan)
                cells.append(f"{coef[1]:+.4f} ({np.sqrt(cov[1, 1]):.4f})")
            out.append(f"| {point} | {floor} | {len(group)} | {cells[0]} | {cells[1]} |")
    return "\n".join(out) + "\n"


def summary(rows: list[dict]) -> str:
    return arm_summary(rows, POINTS, ARMS, REFERENCE_ARM, keys=("mfr", "pd", "coverage", "flow_trend_z"),
                       extra={"heap at the window's end (h^2)": lambda ran: (
                           f"{np.nanmedian([number(r.get('heap_end_h2')) for r in ran]):.2f}"),
                           "flagged": lambda ran: f"{sum(str(r.get('flagged')) == 'True' for r in ran)} of {len(ran)}"}
                       ) + trend_lines(rows)


def figure(rows: list[dict], path: Path, d2_scene: dict) -> None:
    """MFR and PD against the heap's reserve, a panel per target, a line per point and floor: the
    seeds' mean and its SE (usable cases), the shipped reserve marked, and where a point's mean lies at
    the heap `d2_scene` (the config's scene of the arm rough_d40) gives there, a star."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    good = usable(rows)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.8), constrained_layout=True)
    colours = {"thin": "tab:blue", "wide": "tab:orange", "corner": "tab:green", "mid": "tab:red", "mid_f45": "tab:purple",
               "low_f": "tab:brown", "mid_f16": "tab:pink",
               "corner_f31": "tab:olive"}
    for ax, key in zip(axes, target_names("base")):
        for point, colour in colours.items():
            for floor, style in (("rough", "-o"), ("flat", "--s")):
                xs, ms, ses = [], [], []
                ran = sorted({number(row["pile_reserve"]) for row in good if row["point"] == point and row["floor"] == floor})
                for r in ran:
                    y = np.array([number(row[key]) for row in good if row["point"] == point
                                  and row["floor"] == floor and number(row["pile_reserve"]) == r])
                    if len(y) >= 2:
                        xs.append(r), ms.append(y.mean()), ses.append(y.std(ddof=1) / np.sqrt(len(y)))
                if xs:
                    f, d, h, _ = POINTS[point]
                    ax.errorbar(xs, ms, yerr=ses, fmt=style, color=colour, capsize=3, ms=4,
                                label=f"{point} (f {f:g}, h/d {h / d:.1f}), {floor} floor")
                    if floor == "rough" and point not in ("thin", "wide"):  # 40 d^2 (scene.pile_reserve_d2)
                        rule = standing_reserve_h2(d2_scene, d, h, f)
                        at = [m for x, m in zip(xs, ms) if abs(x - rule) < 1e-3]
                        if at:
                            ax.plot([rule], at, marker="*", ms=13, color=colour, ls="none", mec="k", mew=0.6)
        ax.axvline(4.7, color="grey", lw=0.8, ls=":")
        ax.set_xscale("log", base=2)
        ax.set_xticks(RESERVES, [f"{r:g}" for r in RESERVES])
        ax.set_xlabel("heap reserve ahead of the blade (scene.pile_reserve, h^2)")
        ax.set_ylabel(key.upper() + " (mean of the seeds +- SE)")
        ax.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8)
    fig.suptitle("Does the heap decide the answer? (adhesive default scene, default preset; dotted: 4.7 h^2; star: 40 d^2)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--plan", action="store_true", help="print each case's planned size and modelled CPU, run nothing")
    ap.add_argument("--figure", help="draw MFR and PD against the reserve to this PNG")
    add_arguments(ap, POINTS, ARMS, ARMS, "/tmp/heap_size")
    ap.set_defaults(points=["thin", "wide"])
    if "--plan" in sys.argv:  # --csv is not needed to plan
        args = ap.parse_args(sys.argv[1:] + ["--csv", "-"])
        plan(spreadmap_config.load(args.config))
        return
    args = ap.parse_args()
    base = spreadmap_config.load(args.config)
    out = Path(args.csv)
    rows = read_rows(out)
    if not args.summary_only:
        order = {arm: i for i, arm in enumerate(ARMS)}
        todo = pending(rows, args, lambda j: (j[2], list(POINTS).index(j[1]), order[j[0]]))
        jobs = [{"base": base, "arm": a, "point": p, "seed": s, "keep": args.keep} for a, p, s in todo]
        print(f"{len(jobs)} cases to run ({len(rows)} already in {out})", flush=True)
        run_jobs(jobs, run_one, rows, out, COLUMNS, workers=args.workers, describe=lambda row: (
            f"{row['arm']:11s} {row['point']:5s} s{row['seed']} {row.get('status')} mfr {number(row.get('mfr')):.4f} "
            f"pd {number(row.get('pd')):.4f} heap {number(row.get('heap_end_h2')):.2f} h^2 "
            f"trend z {number(row.get('flow_trend_z')):+.2f} n {row.get('n_particles')} cpu {row['cpu_time']:.0f} s "
            f"{row.get('flag_reason') or ''}"))
    text = summary(read_rows(out))
    print(text)
    if args.summary:
        write_text_atomically(Path(args.summary), text)
    if args.figure:
        figure(read_rows(out), Path(args.figure), arm_config(base, "rough_d40")["scene"])


if __name__ == "__main__":
    main()
