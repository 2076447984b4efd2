#!/usr/bin/env python
"""The metrics of raw YADE records (results/cases/*/raw.json), old and new side by side: MFR by
centre count against MFR across the plane, PD to the blade against PD a clearance behind it, the
case's noise estimates (counting statistics and batch means within the case), the layer's
quality and the regime by the old (PD and its slice CV) and the new (coverage, thickness) rule,
with the time taken per case.

    .venv/bin/python benchmarks/layer_metrics.py results/cases/*/raw.json
    .venv/bin/python benchmarks/layer_metrics.py --config config.yaml --csv out.csv a/raw.json b/raw.json
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from spreadmap import config as spreadmap_config
from spreadmap.metrics import case_metrics, layer_density, powder, sphere_volume

ROOT = Path(__file__).resolve().parent.parent

OLD_RULE = {"jam_mfr_max": 0.05, "short_feed_pd_min": 0.20, "short_feed_cv_max": 0.35, "pd_slices": 4}


def old_metrics(raw: dict) -> dict:
    """The metrics as the study's code computed them before: MFR by sphere centres, PD in the box
    ending at the blade, the regime from PD and its 4-slice CV."""
    p = raw["params"]
    s1, s2 = raw["snapshots"]["window_start"], raw["snapshots"]["window_end"]
    v = sphere_volume(p["diameter"])

    def behind(s):
        pos, _ = powder(s)
        return np.count_nonzero(pos[:, 0] < s["blade_rear_x"]) * v + s.get("removed_behind_volume", 0.0)

    mfr = (behind(s2) - behind(s1)) / (p["gap"] * p["width"] * (s2["blade_rear_x"] - s1["blade_rear_x"]))
    pos, rad = powder(s2)
    slices = layer_density(pos, rad, s1["blade_rear_x"], s2["blade_rear_x"], p["width"], p["gap"], OLD_RULE["pd_slices"])
    pd_, cv = float(np.mean(slices)), float(np.std(slices) / np.mean(slices))
    regime = ("jamming" if mfr < OLD_RULE["jam_mfr_max"] else
              "short_feed" if pd_ < OLD_RULE["short_feed_pd_min"] or cv > OLD_RULE["short_feed_cv_max"] else "normal")
    return {"mfr_centres": mfr, "pd_to_blade": pd_, "pd_cv_to_blade": cv, "regime_old": regime}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("raw", nargs="+")
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--csv")
    args = ap.parse_args(argv)
    config = spreadmap_config.load(args.config)
    rows = []
    for path in args.raw:
        with open(path) as fh:
            raw = json.load(fh)
        t = time.perf_counter()
        m = case_metrics(raw, config["regime"], config["stability"], config["metrics"])
        m["metrics_s"] = time.perf_counter() - t
        m["path"] = path
        if raw["status"] == "ok":
            m.update(old_metrics(raw))
        m["h_over_d"] = m["h_um"] / m["d_um"]
        rows.append(m)
    table = pd.DataFrame(rows)
    cols = ["case_id", "h_over_d", "status", "mfr_centres", "mfr", "n_passed", "mfr_sd", "mfr_sd_within",
            "pd_to_blade", "pd", "n_pd", "pd_sd", "pd_cv", "layer_fill", "coverage", "roughness_d", "thickness_ratio",
            "regime_old", "regime", "metrics_s"]
    pd.set_option("display.width", 250)
    print(table[[c for c in cols if c in table]].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    ok = table[table["status"] == "ok"]
    if len(ok) > 2:
        print(f"PD / MFR: {np.min(ok['pd'] / ok['mfr']):.3f}-{np.max(ok['pd'] / ok['mfr']):.3f}; "
              f"layer_fill x thickness_ratio / PD: "
              f"{np.min(ok['layer_fill'] * ok['thickness_ratio'] / ok['pd']):.3f}-"
              f"{np.max(ok['layer_fill'] * ok['thickness_ratio'] / ok['pd']):.3f}")
        for col in ("layer_fill", "coverage", "roughness_d", "thickness_ratio", "pd"):
            r = np.corrcoef(ok["mfr"], ok[col])[0, 1]
            print(f"correlation with MFR across these cases: {col} r = {r:.2f}")
        ratio = ok["mfr_sd_within"] / ok["mfr_sd"]
        print(f"mfr_sd_within / mfr_sd: median {np.nanmedian(ratio):.2f}, range {np.nanmin(ratio):.2f}-{np.nanmax(ratio):.2f}")
    if args.csv:
        table.to_csv(args.csv, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
