"""The factor from one preset to the reference, measured on paired cases (config `fidelity_correction`).

A pair is one design point and one packing seed run at the preset and at the reference (the same
settled cloud draws, so the pair shares what the seed does before the presets part). Per pair and
target the log ratio l = ln(reference / preset) and its noise variance from the two cases' stated
SDs, v = (sd_ref / ref)^2 + (sd_preset / preset)^2. Per point the mean of its pairs' l and v / pairs.

The factor is for every point of a map, most of them never run at the reference, so the points are
a sample of the design space and the factor may differ between them. Cochran's Q of the points
against a common factor (chi-square, points - 1 dof) and DerSimonian and Laird's moment estimate of
the between-point SD tau say whether they differ beyond their noise (reported). What a map needs is
the factor at a point the study did not run: the prediction interval of a new point from the k
points' log ratios l_i (their plain mean m and SD s, which holds their noise as well as tau),

    ln factor at a new point in  m +- t_{k-1, 0.975} s sqrt(1 + 1/k),

stated to the maps as factor = exp(m) and SD = factor x t_{k-1, 0.975} s sqrt(1 + 1/k) / 1.96, so that
their +-1.96 SD is this interval. On synthetic studies of known factor, spread and noise
(tests/fidelity/test_fidelity_correction.py) it held a fresh point's true factor 97-99.9 % of the time at 4-8 points:
on the wide side, because s counts the points' own noise as spread. The random-effects interval
sqrt(SE^2 + tau^2) held it only 82-84 % of the time (tau is often estimated 0 from a few points), and
with Higgins' t_{k-2} 87-91 %: both too narrow. A weighted slope of l on ln(h/d) with its SE says
whether the factor follows the gap.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats

from spreadmap import targets as registry
from spreadmap.design import NAMES, h_over_d
from spreadmap.table import usable_cases as usable

TARGETS = registry.names("base")  # mfr, pd


def pairs(table: pd.DataFrame, preset: str, reference: str, targets=TARGETS) -> pd.DataFrame:
    """One row per (point name, seed) run usable at both presets: l and v per target, h/d, CPU.

    Parameters
    ----------
    table : pandas.DataFrame
        The paired cases' results table: ``preset``, ``name``, ``seed``, ``status`` (and
        ``flagged``), the four parameters, ``cpu_time`` [s] and, per target, its value and its
        stated noise SD ``<t>_sd``.
    preset : str
        The preset to correct.
    reference : str
        The preset it is corrected to.
    targets : sequence of str, optional
        The targets.

    Returns
    -------
    pandas.DataFrame
        Sorted by h/d, name and seed: ``name``, ``seed``, the four parameters, ``h_over_d``,
        ``cpu_preset`` and ``cpu_ref`` [s] and per target ``<t>_preset``, ``<t>_ref``, ``<t>_l``
        (ln(reference / preset)) and ``<t>_v`` (its noise variance).
    """
    keep = ["name", "seed", *NAMES, "cpu_time"] + [c for t in targets for c in (t, f"{t}_sd")]
    a = usable(table[table["preset"] == preset])[keep]
    b = usable(table[table["preset"] == reference])[["name", "seed", "cpu_time"] + [c for t in targets for c in (t, f"{t}_sd")]]
    both = a.merge(b, on=["name", "seed"], suffixes=("_preset", "_ref"))
    out = both[["name", "seed", *NAMES]].copy()
    out["h_over_d"] = h_over_d(out)
    out["cpu_preset"], out["cpu_ref"] = both["cpu_time_preset"], both["cpu_time_ref"]
    for t in targets:
        ref, pre = both[f"{t}_ref"], both[f"{t}_preset"]
        out[f"{t}_preset"], out[f"{t}_ref"] = pre, ref
        out[f"{t}_l"] = np.log(ref / pre)
        out[f"{t}_v"] = (both[f"{t}_sd_ref"] / ref) ** 2 + (both[f"{t}_sd_preset"] / pre) ** 2
    return out.sort_values(["h_over_d", "name", "seed"]).reset_index(drop=True)


def per_point(p: pd.DataFrame, target: str) -> pd.DataFrame:
    g = p.groupby("name", sort=False)
    out = g.agg(h_over_d=("h_over_d", "first"), pairs=("seed", "size"), l=(f"{target}_l", "mean"),
                v_sum=(f"{target}_v", "sum"))
    out["v"] = out["v_sum"] / out["pairs"] ** 2  # the variance of a mean of independent pairs
    out["se"] = np.sqrt(out["v"])
    out["seed_sd"] = g[f"{target}_l"].std(ddof=1)  # the pairs' own spread (1 dof at 2 seeds): a check on v
    return out.drop(columns="v_sum").reset_index()


def random_effects(lr: np.ndarray, v: np.ndarray) -> dict:
    """DerSimonian-Laird pooled mean of lr with within-variances v: mu, its SE, tau, Q and its p."""
    lr, v = np.asarray(lr, float), np.asarray(v, float)
    k = len(lr)
    w = 1.0 / v
    mu_fixed = float(np.sum(w * lr) / np.sum(w))
    q = float(np.sum(w * (lr - mu_fixed) ** 2))
    denominator = float(np.sum(w) - np.sum(w**2) / np.sum(w))
    tau2 = max(0.0, (q - (k - 1)) / denominator) if k > 1 else 0.0
    w_star = 1.0 / (v + tau2)
    mu = float(np.sum(w_star * lr) / np.sum(w_star))
    se = float(1.0 / math.sqrt(np.sum(w_star)))
    return {"mu": mu, "se": se, "tau": math.sqrt(tau2), "q": q, "dof": k - 1,
            "q_p": float(stats.chi2.sf(q, k - 1)) if k > 1 else float("nan"), "mu_fixed": mu_fixed}


def new_point_interval(lr) -> tuple[float, float, float]:
    """(mean, SD, 95 % half-width) of the log factor at a new point from the points' log ratios lr:
    m, s and t_{k-1, 0.975} s sqrt(1 + 1/k) (NaN below two points)."""
    lr = np.asarray(lr, float)
    k = len(lr)
    if k < 2:
        return (float(lr.mean()) if k else float("nan")), float("nan"), float("nan")
    s = float(np.std(lr, ddof=1))
    return float(lr.mean()), s, float(stats.t.ppf(0.975, k - 1) * s * math.sqrt(1.0 + 1.0 / k))


def slope_on_gap(points: pd.DataFrame) -> tuple[float, float]:
    """Weighted least-squares slope of the points' l on ln(h/d) (weights 1 / v) and its SE."""
    x, y, w = np.log(points["h_over_d"].to_numpy(float)), points["l"].to_numpy(float), 1.0 / points["v"].to_numpy(float)
    xm = np.sum(w * x) / np.sum(w)
    sxx = np.sum(w * (x - xm) ** 2)
    return float(np.sum(w * (x - xm) * (y - np.sum(w * y) / np.sum(w))) / sxx), float(1.0 / math.sqrt(sxx))


def correction(table: pd.DataFrame, preset: str = "default", reference: str = "reference", targets=TARGETS) -> dict:
    """Per target: the factor for a map (exp(mu)), its SD at a point not run, and the evidence.

    See the module docstring for the prediction interval of a new point and why it is used.

    Parameters
    ----------
    table : pandas.DataFrame
        The paired cases' results table (see ``pairs``).
    preset : str, optional
        The preset to correct.
    reference : str, optional
        The preset it is corrected to.
    targets : sequence of str, optional
        The targets.

    Returns
    -------
    dict
        ``preset``, ``reference``, ``pairs``, ``points``, ``cpu_ratio`` (reference CPU over the
        preset's) and ``targets``: per target the ``factor`` (exp(m)), its ``sd`` at a point not
        run, ``new_point_95`` and ``mean_95`` intervals, ``random_effects`` (DerSimonian-Laird:
        mu, se, tau, Cochran's q, dof, q_p), ``slope_ln_hd`` and ``slope_se``, and ``per_point``.
    """
    p = pairs(table, preset, reference, targets)
    out = {"preset": preset, "reference": reference, "pairs": int(len(p)), "points": int(p["name"].nunique()),
           "cpu_ratio": float(p["cpu_ref"].sum() / p["cpu_preset"].sum()) if len(p) else float("nan"), "targets": {}}
    for t in targets:
        pts = per_point(p, t)
        re = random_effects(pts["l"], pts["v"])
        slope, slope_se = slope_on_gap(pts) if len(pts) > 2 else (float("nan"), float("nan"))
        k = len(pts)
        m, s, half = new_point_interval(pts["l"])
        factor = math.exp(m)
        out["targets"][t] = {"random_effects": re, "mean_log": m, "sd_log_points": s, "k": k, "factor": factor,
                             "sd": factor * half / 1.96, "new_point_95": [math.exp(m - half), math.exp(m + half)],
                             "mean_95": [math.exp(m - stats.t.ppf(0.975, k - 1) * s / math.sqrt(k)),
                                         math.exp(m + stats.t.ppf(0.975, k - 1) * s / math.sqrt(k))] if k > 1 else None,
                             "slope_ln_hd": slope, "slope_se": slope_se,
                             "per_point": pts.to_dict(orient="records")}
    return out


def config_block(result: dict, source: str, floor: str | None = None) -> dict:
    """The `fidelity_correction` config section of a result (``floor``: scene.substrate.kind of its cases).

    Parameters
    ----------
    result : dict
        The result of ``correction``.
    source : str
        Where the result comes from, written as the section's ``source``.
    floor : str or None, optional
        scene.substrate.kind of its cases; None: no ``floor`` key.

    Returns
    -------
    dict
        ``preset``, ``reference``, ``floor`` (if given), ``source`` and ``targets``: per target
        its ``factor`` and ``sd``, rounded to 4 decimals.
    """
    return {"preset": result["preset"], "reference": result["reference"], **({"floor": floor} if floor else {}), "source": source,
            "targets": {t: {"factor": round(v["factor"], 4), "sd": round(v["sd"], 4)} for t, v in result["targets"].items()}}
