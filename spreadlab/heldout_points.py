"""The held-out check of a finished study: design points that no sweep ran, predicted by the final
surrogate before they run, then run with several packing seeds and scored against the prediction
intervals. Points come from a scrambled Sobol' sequence (scipy.stats.qmc) of their own seed, kept
only when far enough from every case already run, so they test the surrogate between its cases."""
from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd
from scipy import stats
from scipy.stats import qmc

from spreadmap.case.identity import rounded
from spreadmap.design import NAMES, Design, to_physical, to_unit
from spreadmap.table import usable


def choose_points(n: int, ranges: Design | Mapping, ran: pd.DataFrame, min_distance: float = 0.15,
                  seed: int = 2026, prefix: str = "heldout") -> pd.DataFrame:
    """n points of a scrambled Sobol' sequence in the design space, each at least min_distance
    (Euclidean, unit cube) from every point of `ran` (the cases of every sweep) and from the points
    already chosen, named <prefix>_01, ...

    Parameters
    ----------
    n : int
        Number of points (>= 1).
    ranges : Design or mapping
        The design space (``design.Design``, or the config's ``ranges``): the design space.
    ran : pandas.DataFrame
        The cases already run (the four parameters in physical units); may be empty.
    min_distance : float, optional
        Smallest Euclidean distance in the unit design cube to a case run or a point chosen.
    seed : int, optional
        Seed of the scrambled Sobol' sequence.
    prefix : str, optional
        The points' name prefix.

    Returns
    -------
    pandas.DataFrame
        `n` rows: ``name`` then the four parameters in physical units.

    Raises
    ------
    ValueError
        If ``n < 1``, or when 64 n candidates do not give n such points.
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    candidates = qmc.Sobol(d=len(NAMES), scramble=True, seed=seed).random(int(2 ** math.ceil(math.log2(64 * n))))
    taken = list(to_unit(ran[list(NAMES)].to_numpy(float), ranges)) if len(ran) else []
    chosen = []
    for u in candidates:
        if all(np.linalg.norm(u - t) >= min_distance for t in taken):
            chosen.append(u)
            taken.append(u)
            if len(chosen) == n:
                break
    if len(chosen) < n:
        raise ValueError(f"only {len(chosen)} of {n} held-out points lie {min_distance} (unit cube) from every case "
                         f"run; lower min_distance")
    out = pd.DataFrame(to_physical(np.asarray(chosen), ranges), columns=list(NAMES))
    out.insert(0, "name", [f"{prefix}_{i + 1:02d}" for i in range(n)])
    return out


def score(predictions: pd.DataFrame, cases: pd.DataFrame, target: str, level: float = 0.95) -> tuple[pd.DataFrame, dict]:
    """Each held-out point's seed mean against its prediction made before the runs.

    predictions: one row per point (`name`, `<target>`, `<target>_model_sd`, `<target>_run_sd` as
    spreadmap.surrogate.predict writes them). cases: one row per run (`name`, `<target>`), usable
    runs only. The seed mean of n runs has SD sqrt(model_sd^2 + noise^2 / n) about the
    prediction, noise^2 = run_sd^2 - model_sd^2 (the SD of one new run, less the model's part).
    Returns the per-point table (mean, n, prediction, sd, z, inside) and the summary: coverage of
    the `level` intervals with its Clopper-Pearson interval (scipy.stats.binomtest), RMSE of the
    seed means against the prediction and the RMSE the stated SDs predict, the mean of z^2 (1 when
    the SDs are right) and its chi-square test's two tails: ``p_sd_right`` (small when the SDs are
    too small: the intervals too narrow) and ``p_sd_too_wide`` (small when they are too large).

    Parameters
    ----------
    predictions : pandas.DataFrame
        One row per point, made before the runs (see above).
    cases : pandas.DataFrame
        One row per usable run (``match_runs``).
    target : str
        The target scored.
    level : float, optional
        The level of the prediction intervals whose coverage is counted.

    Returns
    -------
    table : pandas.DataFrame
        One row per point with a prediction and a usable run: ``name``, the prediction and its
        SDs, ``seed_mean``, ``n_runs``, ``seed_sd``, ``sd_of_mean``, ``error``, ``z``, ``inside``.
    summary : dict
        ``target``, ``level``, ``points``, ``inside``, ``coverage`` with ``coverage_low`` and
        ``coverage_high``, ``rmse``, ``rmse_expected``, ``mean_z2``, ``p_sd_right`` and
        ``p_sd_too_wide``.

    Raises
    ------
    ValueError
        If no point has both a prediction and a usable run.
    """
    z_level = stats.norm.ppf(0.5 + level / 2.0)
    by_point = cases.groupby("name")[target].agg(["mean", "count", "std"]).rename(
        columns={"mean": "seed_mean", "count": "n_runs", "std": "seed_sd"})
    table = predictions.set_index("name")[[target, f"{target}_model_sd", f"{target}_run_sd"]].join(by_point, how="inner")
    if table.empty:
        raise ValueError("no held-out point has both a prediction and a usable run")
    model_sd, run_sd = table[f"{target}_model_sd"], table[f"{target}_run_sd"]
    noise_var = np.clip(run_sd ** 2 - model_sd ** 2, 0.0, None)
    table["sd_of_mean"] = np.sqrt(model_sd ** 2 + noise_var / table["n_runs"])
    table["error"] = table["seed_mean"] - table[target]
    table["z"] = table["error"] / table["sd_of_mean"]
    table["inside"] = table["z"].abs() <= z_level
    k, n = int(table["inside"].sum()), len(table)
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=0.95, method="exact")
    summary = {"target": target, "level": level, "points": n, "inside": k, "coverage": k / n,
               "coverage_low": ci.low, "coverage_high": ci.high,
               "rmse": float(np.sqrt(np.mean(table["error"] ** 2))),
               "rmse_expected": float(np.sqrt(np.mean(table["sd_of_mean"] ** 2))),
               "mean_z2": float(np.mean(table["z"] ** 2)),
               # chi-square tests of "the stated SDs are right": sum z^2 ~ chi2(n); the upper tail asks
               # whether they are too small (intervals too narrow), the lower tail whether too large
               "p_sd_right": float(stats.chi2.sf(np.sum(table["z"] ** 2), n)),
               "p_sd_too_wide": float(stats.chi2.cdf(np.sum(table["z"] ** 2), n))}
    return table.reset_index(), summary


def runs_of(points: pd.DataFrame, seeds: list[int], preset: str) -> pd.DataFrame:
    """The points file to run (the README's points format: name, preset, seed, f, d_um, h_um,
    v_mm_s), one row per point and packing seed, each point rounded as it will be simulated.

    Parameters
    ----------
    points : pandas.DataFrame
        The held-out points (``choose_points``).
    seeds : list of int
        The packing seeds each point runs with.
    preset : str
        The preset the runs use.

    Returns
    -------
    pandas.DataFrame
        Columns ``name``, ``preset``, ``seed`` and the four parameters (rounded,
        ``spreadmap.case.identity.rounded``).
    """
    rows = [{"name": r["name"], "preset": preset, "seed": int(s), **rounded(r)} for _, r in points.iterrows()
            for s in seeds]
    return pd.DataFrame(rows, columns=["name", "preset", "seed", *NAMES])


def match_runs(points: pd.DataFrame, table: pd.DataFrame) -> pd.DataFrame:
    """The usable rows of a results table (spreadmap.table.usable) that ran a held-out point, with
    the point's name: matched on the rounded design point, as the workflow names its cases.

    Parameters
    ----------
    points : pandas.DataFrame
        The held-out points (``name`` and the four parameters).
    table : pandas.DataFrame
        A results table.

    Returns
    -------
    pandas.DataFrame
        The matching usable rows of `table`, with a ``name`` column.
    """
    key = lambda r: tuple(rounded(r)[n] for n in NAMES)  # noqa: E731
    names = {key(r): r["name"] for _, r in points.iterrows()}
    ok = table[usable(table)].copy()
    ok["name"] = [names.get(key(r)) for _, r in ok.iterrows()]
    return ok[ok["name"].notna()]
