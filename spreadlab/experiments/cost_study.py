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
The study is run by benchmarks/cost_study.py.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

METHODS = ("lds", "active", "active_per_cpu")


def cpu_needed(table: pd.DataFrame, target: float) -> pd.DataFrame:
    """Per method and seed: CPU hours spent when the map RMSE first reached ``target``, and the run's CPU hours.

    Parameters
    ----------
    table : pandas.DataFrame
        ``noisy_study.run``'s table: ``method``, ``seed``, ``n``, ``map_rmse`` and ``cpu_cases`` [s]
        (the cases' CPU so far).
    target : float
        The map-RMSE target (MFR units, dimensionless).

    Returns
    -------
    pandas.DataFrame
        One row per (method, seed): ``method``, ``seed``, ``target``, ``cpu_h`` [h] (the CPU of the
        first checkpoint at or below the target; NaN: not within the run), ``cases`` (its n; NaN
        likewise) and ``run_cpu_h`` [h] (the CPU the run spent in all).
    """
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
    """Median and range over seeds of the CPU hours and cases needed per method and target; per-seed ratios.

    The per-seed ratio baseline / candidate of the CPU hours: a seed where only one reached the
    target is left out of the ratio and counted in ``not_reached``.

    Parameters
    ----------
    needed : pandas.DataFrame
        ``cpu_needed``'s tables (one or several targets).
    baseline : str, optional
        The method in the ratio's numerator.
    candidate : str, optional
        The method in its denominator; its rows carry the ratio.

    Returns
    -------
    pandas.DataFrame
        One row per (method, target): ``runs``, ``not_reached``, ``cpu_h_median``, ``cpu_h_min``,
        ``cpu_h_max`` [h] and ``cases_median`` over the seeds that reached it; the candidate's rows
        also ``ratio_<baseline>_median``, ``_min``, ``_max`` and ``paired_seeds``.
    """
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
