#!/usr/bin/env python
"""How fast is this machine today, against the one that made the published times (issue 64)?

Runs the shipped main job's median-cost case and (unless --quick) its costliest case (the d ~10 um,
h/d ~7 corner, which loses most on a slow day) from a published run's cases table, each in its own
process with Debian's YADE, and prints each case's CPU against the published CPU, the geometric mean
(the machine's speed factor: multiply a published time by it), and whether MFR and PD came out the
same to the bit (they should: identical -j1 runs give identical results; a mismatch means a
different scene, not a different speed).

    .venv/bin/python benchmarks/machine_speed.py            # ~1 min median case + ~5 min corner
    .venv/bin/python benchmarks/machine_speed.py --quick    # the median case only

The published times this factor scales: README and docs/main_job (run 2026-12-07e). Run it with the
cores otherwise idle; two cases run one after the other, one core each.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from pathlib import Path

import pandas as pd

from spreadmap import config as spreadmap_config
from spreadmap.case.identity import case_scene
from spreadmap.case.launcher import run_case
from spreadmap.case.render import render
from spreadmap.design import NAMES
from spreadmap.metrics.case import case_metrics

ROOT = Path(__file__).resolve().parent.parent
PUBLISHED = ROOT / "docs" / "main_job" / "run_2026-12-07e" / "cases.csv"


def reference_cases(table: pd.DataFrame, quick: bool) -> pd.DataFrame:
    """The usable case whose CPU is the run's median (nearest), and the costliest one unless quick."""
    ok = table[(table["status"] == "ok") & (table["flagged"].astype(str) != "True")].copy()
    if ok.empty:
        raise ValueError("the published table has no usable case")
    median = ok.iloc[[int((ok["cpu_time"] - ok["cpu_time"].median()).abs().to_numpy().argmin())]]
    return median if quick else pd.concat([median, ok.loc[[ok["cpu_time"].idxmax()]]])


def run_one(row: pd.Series, cfg: dict, workdir: Path) -> dict:
    point = {k: float(row[k]) for k in NAMES}
    cid, params = case_scene(point, str(row["preset"]), cfg, int(row["seed"]))
    folder = workdir / cid
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "case.py").write_text(render(params))
    result = run_case(folder / "case.py", folder / "raw.json", folder / "run.log", params["timeout_s"])
    raw = folder / "raw.json"
    if not raw.exists():
        raise RuntimeError(f"case {cid} did not finish ({result['outcome']}): {result.get('reason')}")
    out = case_metrics(json.loads(raw.read_text()), cfg["regime"], cfg["stability"], cfg["metrics"])
    return {"point": ", ".join(f"{k} {point[k]:g}" for k in NAMES), "cpu": result["cpu_time"],
            "published_cpu": float(row["cpu_time"]), "same": out["mfr"] == row["mfr"] and out["pd"] == row["pd"],
            "mfr": out["mfr"], "published_mfr": float(row["mfr"])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default=str(PUBLISHED), help="the published cases table (default run 2026-12-07e)")
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--quick", action="store_true", help="the median case only")
    args = ap.parse_args(argv)
    cfg = spreadmap_config.load(args.config)
    chosen = reference_cases(pd.read_csv(args.cases, float_precision="round_trip"), args.quick)  # to the bit
    ratios = []
    with tempfile.TemporaryDirectory(prefix="machine_speed_") as tmp:
        for _, row in chosen.iterrows():
            r = run_one(row, cfg, Path(tmp))
            ratios.append(r["cpu"] / r["published_cpu"])
            print(f"{r['point']}: CPU {r['cpu']:.1f} s against {r['published_cpu']:.1f} s published "
                  f"({ratios[-1]:.2f}x); MFR {r['mfr']:.6f} "
                  + ("the same to the bit" if r["same"] else f"DIFFERS from the published {r['published_mfr']:.6f}"),
                  flush=True)
    factor = math.exp(sum(map(math.log, ratios)) / len(ratios))
    print(f"this machine today: {factor:.2f}x the published CPU (geometric mean of {len(ratios)} case(s)); "
          f"a published time of 21.6 min to the maps reads ~{21.6 * factor:.0f} min here")
    return 0


if __name__ == "__main__":
    sys.exit(main())
