"""The noise law checked on seed-repeat cells it did not see.

Leave-one-point-out: every cell at a design point (all its presets and arms) is predicted by the
law fitted on the cells of the other points. If the law is right, a held-out cell's
u = s^2 / sigma_hat^2 follows chi2_nu / nu (nu = seeds - 1; the fitted sigma's own error is left
out: an SE of ~0.07 on ln sigma at the published cells' median, against an SD of ln s^2 of ~1 at
2-3 dof), so

* the pooled ratio R = sum nu u / sum nu (observed over predicted variance) is 1; its interval is
  given two ways, chi-square (exact if the cells scatter about the law as chi2_nu / nu, R x D ~
  chi2_D, D = sum nu) and a percentile bootstrap over design points (which also holds when cells
  scatter more than that, but is rough with few points); the verdict is read from the union of
  the two, so that it calls a scale wrong only when both intervals exclude 1;
* a case's interval, value +- z_0.95 SD (90 %), holds its seeds 90 % of the time: each seed's
  deviation from its cell's mean, scaled by sqrt(k / (k - 1)), has the SD of one case, so the share
  of seeds inside +- 1.645 predicted SDs is the coverage of the 90 % interval the SD gives a case;
  its interval is the union of a bootstrap over design points (a cell's deviations sum to zero, so
  seeds are not independent) and Clopper-Pearson over seeds (which the bootstrap needs with few
  points, where it degenerates);
* each cell's PIT, F_chi2_nu(nu u), is uniform (Kolmogorov-Smirnov test): the shape of the scatter.

A verdict is "too narrow" when the interval says the predicted SDs are too small (R above 1,
coverage below nominal), "too wide" when they are too large, otherwise "consistent". (The central
interval of s^2 itself is no measure of width: with 1-3 dof a too-large SD moves the cells below its
lower end, and its coverage falls either way.)
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from spreadlab.noise_law.fit import LAW, fit_law
from spreadmap.surrogate.validation import verdict  # an interval against a null, as the surrogate's check reads it


def leave_point_out(cells: pd.DataFrame, terms=LAW, fixed: dict | None = None, group: str = "point") -> pd.DataFrame:
    """The cells with `sd_pred`, each from the law fitted without its group's cells, and `u`, `pit`.

    Parameters
    ----------
    cells : pandas.DataFrame
        Seed-repeat cells of one target (``spreadlab.noise_law.cells.seed_cells``).
    terms : sequence of str, optional
        The law's terms (``spreadlab.noise_law.fit.fit_law``).
    fixed : dict or None, optional
        Terms held at given values.
    group : str, optional
        The column whose values are left out one at a time (default: the design point).

    Returns
    -------
    pandas.DataFrame
        A copy of `cells` with ``sd_pred`` (the held-out law's SD of one case, the target's units)
        and the columns of ``scored``.

    Raises
    ------
    ValueError
        If the law cannot be fitted without a group's cells (``fit_law``).
    """
    out = cells.copy()
    pred = np.full(len(cells), np.nan)
    for key in cells[group].unique():
        held = (cells[group] == key).to_numpy()
        law = fit_law(cells[~held], terms, fixed)
        pred[held] = law.sd(cells[held])
    return scored(out.assign(sd_pred=pred))


def scored(cells: pd.DataFrame, sd_col: str = "sd_pred") -> pd.DataFrame:
    """`u` = s^2 / predicted variance, its PIT under chi2_nu / nu, and `inside`, the seeds within the
    90 % interval of a case (+- 1.645 predicted SDs of the cell's mean), for a column of predicted SDs.

    Parameters
    ----------
    cells : pandas.DataFrame
        Seed-repeat cells with ``s2``, ``dof``, ``dev`` (each seed's scaled deviation) and the
        predicted SD column.
    sd_col : str, optional
        The column of predicted SDs of one case (the target's units).

    Returns
    -------
    pandas.DataFrame
        A copy of `cells` with ``u``, ``pit`` and ``inside`` (a count of seeds).
    """
    u = cells["s2"] / cells[sd_col] ** 2
    z = stats.norm.ppf(0.95)
    inside = [int(np.sum(np.abs(dev) <= z * sd)) for dev, sd in zip(cells["dev"], cells[sd_col])]
    return cells.assign(u=u, pit=stats.chi2.cdf(cells["dof"] * u, cells["dof"]), inside=inside)


def predictive_check(cells: pd.DataFrame, group: str = "point", level: float = 0.95,
                     boots: int = 2000, seed: int = 0) -> dict:
    """Summary of scored cells (`u`, `pit`, `inside`, `dof`, `seeds`): the pooled variance ratio with
    its chi-square and bootstrap-over-`group` intervals, the coverage of a case's 90 % interval with
    its bootstrap interval, the KS p value of the PITs, and the verdicts.

    Parameters
    ----------
    cells : pandas.DataFrame
        Scored cells (``scored`` or ``leave_point_out``).
    group : str, optional
        The column the bootstrap resamples by (default: the design point).
    level : float, optional
        Confidence level of the intervals.
    boots : int, optional
        Bootstrap resamples.
    seed : int, optional
        Seed of the bootstrap's random generator.

    Returns
    -------
    dict
        ``cells``, ``points``, ``dof``; the pooled variance ratio ``ratio`` with
        ``ratio_chi2_lo``/``_hi`` and ``ratio_boot_lo``/``_hi``, ``sd_ratio`` (its square root) and
        ``verdict``; ``seeds``, ``coverage90`` with ``coverage90_lo``/``_hi`` (the union of the
        bootstrap and Clopper-Pearson intervals) and ``coverage_verdict``; ``ks_p``.
    """
    dof, u = cells["dof"].to_numpy(float), cells["u"].to_numpy(float)
    seeds, inside = cells["seeds"].to_numpy(float), cells["inside"].to_numpy(float)
    D = dof.sum()
    ratio = float(np.sum(dof * u) / D)
    tail = (1 - level) / 2
    chi_lo, chi_hi = ratio * D / stats.chi2.ppf([1 - tail, tail], D)
    keys = cells[group].to_numpy()
    uniq = np.unique(keys)
    index = [np.flatnonzero(keys == k) for k in uniq]
    sums = np.array([[np.sum(dof[i] * u[i]), np.sum(dof[i]), np.sum(inside[i]), np.sum(seeds[i])] for i in index])
    rng = np.random.default_rng(seed)
    draw = sums[rng.integers(0, len(uniq), size=(boots, len(uniq)))].sum(axis=1)
    b_lo, b_hi = np.quantile(draw[:, 0] / draw[:, 1], [tail, 1 - tail])
    c_lo, c_hi = np.quantile(draw[:, 2] / draw[:, 3], [tail, 1 - tail])
    exact = stats.binomtest(int(inside.sum()), int(seeds.sum())).proportion_ci(level, method="exact")
    c_lo, c_hi = min(c_lo, exact.low), max(c_hi, exact.high)
    return {"cells": len(cells), "points": len(uniq), "dof": int(D), "ratio": ratio,
            "ratio_chi2_lo": float(chi_lo), "ratio_chi2_hi": float(chi_hi),
            "ratio_boot_lo": float(b_lo), "ratio_boot_hi": float(b_hi),
            "sd_ratio": float(np.sqrt(ratio)),
            "verdict": verdict(min(chi_lo, b_lo), max(chi_hi, b_hi), 1.0, "too narrow", "too wide"),
            "seeds": int(seeds.sum()), "coverage90": float(inside.sum() / seeds.sum()),
            "coverage90_lo": float(c_lo), "coverage90_hi": float(c_hi),
            "coverage_verdict": verdict(c_lo, c_hi, 0.90, "too wide", "too narrow"),
            "ks_p": float(stats.kstest(cells["pit"].to_numpy(float), "uniform").pvalue)}
