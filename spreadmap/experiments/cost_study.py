"""The map per CPU-second: active batches chosen by variance reduction (``active``) against the
same reduction per predicted CPU-second (``active_per_cpu``), and the LDS sequence, on a known
truth at equal CPU.  (No DEM.)

Truth, noise and model are ``noisy_study``'s (the MFR-like function with the counting noise, the
GP refitted at every batch); each case costs the default scene's CPU law (``noisy_study.case_cost``,
25-1350 s, the most at small d and large h/d) with a log-normal scatter of SD 0.19, and
``active_per_cpu`` learns that law from the costs it has observed, as the workflow does.  Every
run is the same for both active designs up to its first batch (same seed: same LDS start, noise
and candidates), so their difference is paired by seed.

Reported (``summarise``): per design and map-RMSE target, the CPU hours each seed needed to reach
the target (the CPU of the first checkpoint at or below it; censored at the budget), their median
and range over seeds, and per seed the ratio of ``active``'s CPU to ``active_per_cpu``'s.

    python -m spreadmap.experiments.cost_study --out docs/sampling --seeds 8 --n-max 256
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pandas as pd

from ..files import write_text_atomically
from .noisy_study import run

METHODS = ("lds", "active", "active_per_cpu")


def cpu_needed(table: pd.DataFrame, target: float) -> pd.DataFrame:
    """Per method and seed: CPU hours spent when the map RMSE first reached ``target`` (NaN: not
    within the run), and the CPU hours the run spent in all."""
    rows = []
    for (method, seed), g in table.groupby(["method", "seed"], sort=False):
        g = g.sort_values("n")
        hit = g.loc[g["map_rmse"] <= target, "cpu_cases"]
        rows.append({"method": method, "seed": int(seed), "target": target,
                     "cpu_h": float(hit.iloc[0]) / 3600 if len(hit) else np.nan,
                     "cases": int(g.loc[hit.index[0], "n"]) if len(hit) else np.nan,
                     "run_cpu_h": float(g["cpu_cases"].max()) / 3600})
    return pd.DataFrame(rows)


def summarise(needed: pd.DataFrame, baseline: str = "active", candidate: str = "active_per_cpu") -> pd.DataFrame:
    """Median and range over seeds of the CPU hours and cases needed per method and target, and
    the per-seed ratio baseline / candidate (a seed where only one reached the target is left
    out of the ratio and counted in ``not_reached``)."""
    rows = []
    for (method, target), g in needed.groupby(["method", "target"], sort=False):
        ok = g["cpu_h"].notna()
        row = {"method": method, "target": target, "runs": len(g), "not_reached": int((~ok).sum()),
               "cpu_h_median": g.loc[ok, "cpu_h"].median(), "cpu_h_min": g.loc[ok, "cpu_h"].min(),
               "cpu_h_max": g.loc[ok, "cpu_h"].max(), "cases_median": g.loc[ok, "cases"].median()}
        if method == candidate:
            base = needed[(needed["method"] == baseline) & (needed["target"] == target)].set_index("seed")["cpu_h"]
            ratio = (base / g.set_index("seed")["cpu_h"]).dropna()
            row.update({f"ratio_{baseline}_median": ratio.median() if len(ratio) else np.nan,
                        f"ratio_{baseline}_min": ratio.min() if len(ratio) else np.nan,
                        f"ratio_{baseline}_max": ratio.max() if len(ratio) else np.nan,
                        "paired_seeds": int(len(ratio))})
        rows.append(row)
    return pd.DataFrame(rows)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--n-max", type=int, default=256)
    ap.add_argument("--n-candidates", type=int, default=2048)
    ap.add_argument("--targets", type=float, nargs="+", default=[0.01, 0.007, 0.005])
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0, c0 = time.time(), time.process_time()
    table = run(METHODS, ["counting"], range(args.seeds), n_max=args.n_max, n_candidates=args.n_candidates,
                log=lambda s: print(s, flush=True), partial=out / "cost_study_runs.partial.csv")
    write_text_atomically(out / "cost_study_runs.csv", table.to_csv(index=False))
    (out / "cost_study_runs.partial.csv").unlink(missing_ok=True)
    needed = pd.concat([cpu_needed(table, t) for t in args.targets], ignore_index=True)
    write_text_atomically(out / "cost_study_needed.csv", needed.to_csv(index=False))
    summary = summarise(needed)
    write_text_atomically(out / "cost_study_summary.csv", summary.to_csv(index=False))
    from .plots import plot_cost_study
    plot_cost_study(table, args.targets, out / "cost_study")
    meta = {"command": "python -m spreadmap.experiments.cost_study " + " ".join(argv or []),
            "wall_s": time.time() - t0, "cpu_s": time.process_time() - c0, "seeds": args.seeds,
            "n_max": args.n_max, "targets": args.targets}
    write_text_atomically(out / "cost_study_run.json", json.dumps(meta, indent=1))
    print(summary.to_string())
    print(json.dumps(meta))


if __name__ == "__main__":
    import sys
    main(sys.argv[1:])
