#!/usr/bin/env python
"""Score the shipped map's blind check at the truth level (issue 64, pre-registered in
docs/truth/README.md): the truth-level runs of docs/truth/blind/points.csv against the predictions
committed before them, into docs/truth/blind.csv (one row per point and target: point, f, d_um,
h_um, v_mm_s, target, predicted, predicted_sd, truth_mean, truth_se, n_seeds) and a summary.

    .venv/bin/python tools/truth_blind.py --table results/tables/points.csv \
        --out docs/truth/blind.csv --summary docs/truth/blind_summary.md

The truth's SE at a point is the pooled seed SD over all points (each point's seed spread, pooled:
2 seeds a point give one degree of freedom each) over sqrt(its seeds). Per target: the RMSE of the
truth means against the predictions, the same net of the truth's own noise (sqrt(mean(err^2) -
mean(se^2)), floored at 0), which passes at <= the tolerance, and the share of the 95 % intervals
(the map's model SD and the truth's SE together) that hold the truth, with its Clopper-Pearson CI,
which passes if it holds 0.95. The decision settings (blind/decision_predictions.csv) are read the
same way: does the truth-level run meet the layer bounds the decision was about?
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from spreadlab.heldout_points import match_runs
from spreadmap.design import NAMES
from spreadmap.design import TARGETS as BASE_TARGETS
from spreadmap.files import write_csv_atomically, write_text_atomically

ROOT = Path(__file__).resolve().parents[1]
BLIND = ROOT / "docs" / "truth" / "blind"
TARGETS = (*BASE_TARGETS, "coverage", "thickness_ratio")  # the map's axes and the decisions' bounds
TOLERANCE = 0.02
COLUMNS = ["point", *NAMES, "target", "predicted", "predicted_sd", "truth_mean", "truth_se", "n_seeds"]


def blind_rows(predictions: pd.DataFrame, runs: pd.DataFrame, targets=TARGETS) -> pd.DataFrame:
    """One row per point and target with a prediction and a usable run (COLUMNS)."""
    rows = []
    for target in targets:
        if target not in runs or target not in predictions:
            continue
        groups = runs.groupby("name")[target]
        spread = groups.agg(lambda x: float(np.var(x, ddof=1)) if len(x) > 1 else math.nan)
        dof = groups.count() - 1
        ok = dof > 0
        pooled = float((spread[ok] * dof[ok]).sum() / dof[ok].sum()) if ok.any() else math.nan
        for _, p in predictions.iterrows():
            x = runs.loc[runs["name"] == p["name"], target].to_numpy(float)
            x = x[np.isfinite(x)]
            if len(x) == 0:
                continue
            rows.append({"point": p["name"], **{n: p[n] for n in NAMES}, "target": target,
                         "predicted": p[target], "predicted_sd": p[f"{target}_model_sd"],
                         "truth_mean": float(x.mean()), "truth_se": math.sqrt(pooled / len(x)), "n_seeds": len(x)})
    return pd.DataFrame(rows, columns=COLUMNS)


def summary(rows: pd.DataFrame, tolerance: float = TOLERANCE) -> pd.DataFrame:
    """Per target: points, RMSE, RMSE net of the truth's noise, the share of 95 % intervals holding
    the truth with its exact 95 % CI, and the verdicts of the pre-registered criteria."""
    out = []
    for target, g in rows.groupby("target", sort=False):
        err = g["truth_mean"] - g["predicted"]
        sd = np.sqrt(g["predicted_sd"] ** 2 + g["truth_se"] ** 2)
        inside = int((err.abs() <= 1.96 * sd).sum())
        ci = stats.binomtest(inside, len(g)).proportion_ci(0.95, method="exact")
        rmse = float(np.sqrt(np.mean(err ** 2)))
        net = float(np.sqrt(max(0.0, np.mean(err ** 2) - np.mean(g["truth_se"] ** 2))))
        out.append({"target": target, "points": len(g), "mean_error": float(err.mean()), "rmse": rmse,
                    "rmse_net_of_noise": net, "inside_95": inside, "coverage": inside / len(g),
                    "coverage_low": ci.low, "coverage_high": ci.high,
                    "rmse_passes": net <= tolerance if target in BASE_TARGETS else None,
                    "coverage_passes": ci.low <= 0.95 <= ci.high})
    return pd.DataFrame(out)


def decisions(predictions: pd.DataFrame, runs: pd.DataFrame, bounds: dict) -> pd.DataFrame:
    """For each decision setting: the truth-level mean of each bounded target, whether it meets the
    bounds, against the probability the decision stated."""
    out = []
    for _, p in predictions.iterrows():
        here = runs[runs["name"] == p["name"]]
        if here.empty:
            continue
        row = {"setting": p["name"], "status": p["status"], "stated_probability": p["probability"], "n_seeds": len(here)}
        meets = True
        for target, bound in bounds.items():
            mean = float(here[target].mean())
            row[f"{target}_truth"] = mean
            meets &= (mean >= bound.get("min", -math.inf)) and (mean <= bound.get("max", math.inf))
        row["meets_bounds"] = bool(meets)
        out.append(row)
    return pd.DataFrame(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--table", required=True, help="a results table holding the truth-level runs of the blind points")
    ap.add_argument("--points", default=str(BLIND / "points.csv"))
    ap.add_argument("--predictions", default=str(BLIND / "predictions.csv"))
    ap.add_argument("--decisions", default=str(BLIND / "decision_predictions.csv"))
    ap.add_argument("--bounds", default="coverage:0.95,thickness_ratio:0.5", help="target:min,... (the shipped bounds)")
    ap.add_argument("--out", default=str(ROOT / "docs" / "truth" / "blind.csv"))
    ap.add_argument("--summary", help="write the summary (markdown) here")
    args = ap.parse_args(argv)
    table = pd.read_csv(args.table)
    points = pd.read_csv(args.points).drop_duplicates("name")
    decision_points = pd.read_csv(args.decisions)
    runs = match_runs(pd.concat([points[["name", *NAMES]], decision_points[["name", *NAMES]]]), table)
    rows = blind_rows(pd.read_csv(args.predictions), runs)
    if rows.empty:
        print("no blind point has a usable truth-level run in the table", file=sys.stderr)
        return 2
    write_csv_atomically(Path(args.out), rows.to_dict("records"), COLUMNS)
    bounds = {k: {"min": float(v)} for k, v in (item.split(":") for item in args.bounds.split(","))}
    text = ("## The blind check\n\n" + summary(rows).to_markdown(index=False, floatfmt=".4f") + "\n\n## The decisions\n\n"
            + decisions(decision_points, runs, bounds).to_markdown(index=False, floatfmt=".4f") + "\n")
    print(text)
    if args.summary:
        write_text_atomically(Path(args.summary), text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
