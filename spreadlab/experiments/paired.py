"""An arm against a base arm, case by case (same point, same packing seed): the numbers of a scene
change's A/B (tools/paired_arms.py prints them; spreadlab.readme_numbers re-derives the README's).

``pairs`` joins the two arms' finished cases; ``cpu_ratio`` is the geometric mean of the pairs' CPU
ratios with a t interval on the log ratios; ``relative_shift`` the pooled mean relative difference
of a target with a t interval; ``by_point`` each point's mean difference and its z against the
cases' recorded SDs (each case's own noise estimate, independent of the difference).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats


def pairs(cases: pd.DataFrame, arm: str, base: str) -> pd.DataFrame:
    """The (point, seed) pairs both arms finished: the arm's columns with suffix ``_arm``, the
    base's with ``_base``.

    Parameters
    ----------
    cases : pandas.DataFrame
        The cases table (``arm``, ``point``, ``seed``, ``status`` and the measured columns).
    arm, base : str
        The two arms' names.

    Returns
    -------
    pandas.DataFrame
        One row per pair, sorted by point and seed.
    """
    done = cases[cases["status"] == "ok"]
    joined = done[done["arm"] == arm].merge(done[done["arm"] == base], on=["point", "seed"], how="inner",
                                            suffixes=("_arm", "_base"))
    return joined.sort_values(["point", "seed"]).reset_index(drop=True)


def flagged(values: pd.Series) -> np.ndarray:
    """A flag column as booleans (True / False or their strings, as a CSV reads back)."""
    return values.astype(str).str.strip().str.lower().isin(("true", "1")).to_numpy()


def cpu_ratio(p: pd.DataFrame, level: float = 0.95) -> tuple[float, float, float]:
    """Geometric mean of the pairs' CPU ratios arm / base and its t interval (on the log ratios)."""
    logs = np.log(p["cpu_time_arm"].to_numpy(float) / p["cpu_time_base"].to_numpy(float))
    n = len(logs)
    mean = float(logs.mean())
    if n < 2:
        return math.exp(mean), math.nan, math.nan
    half = stats.t.ppf(0.5 + level / 2, n - 1) * logs.std(ddof=1) / math.sqrt(n)
    return math.exp(mean), math.exp(mean - half), math.exp(mean + half)


def relative_shift(p: pd.DataFrame, target: str, level: float = 0.90) -> tuple[float, float, float]:
    """The pooled mean of the pairs' (arm - base) / base and its t interval."""
    base = p[f"{target}_base"].to_numpy(float)
    rel = (p[f"{target}_arm"].to_numpy(float) - base) / base
    n = len(rel)
    mean = float(rel.mean())
    if n < 2:
        return mean, math.nan, math.nan
    half = stats.t.ppf(0.5 + level / 2, n - 1) * rel.std(ddof=1) / math.sqrt(n)
    return mean, mean - half, mean + half


def by_point(p: pd.DataFrame, target: str) -> pd.DataFrame:
    """Per point: the seeds paired, the mean difference arm - base, the base's mean, the SE from the
    cases' recorded SDs (the variance of a mean of n differences: the sum of both cases' variances
    over n^2) and z."""
    rows = []
    for point, g in p.groupby("point", sort=True):
        diff = (g[f"{target}_arm"] - g[f"{target}_base"]).to_numpy(float)
        var = (g[f"{target}_sd_arm"].to_numpy(float) ** 2 + g[f"{target}_sd_base"].to_numpy(float) ** 2).sum()
        se = math.sqrt(var) / len(g)
        rows.append({"point": point, "seeds": len(g), "diff": float(diff.mean()),
                     "base": float(g[f"{target}_base"].mean()), "se": se,
                     "z": float(diff.mean()) / se if se > 0 else math.nan})
    return pd.DataFrame(rows)
