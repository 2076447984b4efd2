#!/usr/bin/env python
"""What a size distribution costs per case against spheres of one size, and how far its tails can
be cut before MFR and PD move (issue 51).

Arms (each the shipped config, `default` preset, adhesion as shipped; one thing changed):
  one_size     span 0: spheres of one size d (the scene as before the size distribution);
  span1_d5     a log-normal by volume with D50 = d and span (D90 - D10) / D50 = --span (default 1.0,
               a 15-45 um-like powder at D50 30 um), cut at D5 and D95;
  span1_d1     the same cut at D1 and D99: the reference of the tails question (its smallest sphere
               sets a 0.77x shorter step than D5's at span 1, and there are more of them).
Points: fine / medium / coarse (D50 15 / 30 / 45 um at f 0.3, h 60 um, v 10 mm/s: the points of
benchmarks/adhesion_scaling.py), each with --seeds packing seeds; cases run two at a time, each
in its own process (spreadlab.experiments.arms), cheapest first, every finished case appended to
--csv at once.

    .venv/bin/python benchmarks/psd_cost.py --csv docs/size_distribution/cost_cases.csv \
        --summary docs/size_distribution/cost_summary.md --keep /tmp/psd_cost
"""
from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np

from spreadlab.experiments.arms import add_arguments, arm_summary, number, run_arm_case, run_study
from spreadmap import config as spreadmap_config

ROOT = Path(__file__).resolve().parent.parent
POINTS = {"fine": (0.30, 15.0, 60.0, 10.0), "medium": (0.30, 30.0, 60.0, 10.0), "coarse": (0.30, 45.0, 60.0, 10.0)}
ARMS = {"one_size": None, "span1_d5": [0.05, 0.95], "span1_d1": [0.01, 0.99]}  # arm -> the tails (None: one size)
REFERENCE_ARM = "span1_d1"
COLUMNS = ("arm", "point", "seed", "case_id", "f", "d_um", "h_um", "v_mm_s", "size_span", "status", "flagged",
           "flag_reason", "regime", "mfr", "pd", "mfr_sd", "pd_sd", "n_passed", "coverage", "thickness_ratio",
           "roughness_d", "flow_trend_z", "feed_d10_um", "feed_d50_um", "feed_d90_um", "h_over_d90",
           "layer_d50_ratio", "layer_d50_ratio_sd", "bond_number", "n_particles", "time_step", "steps",
           "peak_overlap_ratio", "peak_overlap_free", "peak_overlap_wedged", "cpu_time", "wall_time")


def arm_config(base: dict, arm: str, span: float) -> dict:
    """The config of an arm: the shipped one with its size distribution set."""
    cfg = copy.deepcopy(base)
    tails = ARMS[arm]
    cfg["material"]["size_distribution"] = ({"span": 0.0, "tails": [0.05, 0.95]} if tails is None
                                            else {"span": span, "tails": tails})
    return cfg


def run_one(job: dict) -> dict:
    f, d, h, v = POINTS[job["point"]]
    row, _ = run_arm_case(arm_config(job["base"], job["arm"], job["span"]), "default",
                          {"f": f, "d_um": d, "h_um": h, "v_mm_s": v}, job["seed"], job["keep"], COLUMNS)
    row.update({"arm": job["arm"], "point": job["point"]})
    return row


def cpu_ratio(rows: list[dict]):
    """The extra column: an arm's median CPU over the one-size arm's at the same point."""
    def cell(ran: list[dict]) -> str:
        point = ran[0]["point"]
        one = [number(r["cpu_time"]) for r in rows if r["point"] == point and r["arm"] == "one_size"]
        mine = [number(r["cpu_time"]) for r in ran]
        if not one:
            return ""
        return f"{np.nanmedian(mine) / np.nanmedian(one):.2f}"
    return cell


def summary(rows: list[dict]) -> str:
    return arm_summary(rows, POINTS, ARMS, REFERENCE_ARM, keys=("mfr", "pd", "coverage", "layer_d50_ratio"),
                       extra={"h / D90": lambda ran: f"{np.nanmedian([number(r['h_over_d90']) for r in ran]):.2f}",
                              "CPU / one size": cpu_ratio(rows)})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--span", type=float, default=1.0)
    add_arguments(ap, POINTS, ARMS, ARMS, "/tmp/psd_cost")
    args = ap.parse_args()
    base = spreadmap_config.load(args.config)
    cost = {"one_size": 0, "span1_d5": 1, "span1_d1": 2}  # cheapest first: one size, coarse first
    run_study(args, lambda j: (cost[j[0]], -POINTS[j[1]][1], j[2]),
              lambda a, p, s: {"base": base, "arm": a, "point": p, "seed": s, "span": args.span, "keep": args.keep},
              run_one, COLUMNS, summary, extra=lambda row: (
                  f"h/D90 {number(row.get('h_over_d90')):.2f} D50 ratio {number(row.get('layer_d50_ratio')):.3f} "
                  f"n {row.get('n_particles')}"))


if __name__ == "__main__":
    main()
