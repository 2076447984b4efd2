"""The noise law refitted for another scene from its few seed repeats, against a base law.

A scene with few seed-repeat cells (the adhesive default: a handful of points) cannot pin down the
law's three coefficients. ``refit`` frees only some of them and holds the others at the base law's
values (the dry scene's, docs/noise):

* ``level``: a alone (the relative SD at N_REF and h/d = HD_REF), b and g held: the scene's noise
  is the base law's times one factor, exp(a - a_base);
* ``level_g``: a and g (the power of h/d), b held: the factor may change with h/d (where h/d is
  mostly d, as in this design box, with the Bond number).

``refit_target`` fits both, their profile intervals, the likelihood-ratio test of g = the base's g,
the level against the base's (with the base held fixed, and from a joint fit of both scenes' cells
with an indicator of the scene, which carries the base's own uncertainty), and each law checked
leave-one-point-out (``leave_one_out``) beside the base law and the stated SDs, both applied as
they are.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from spreadlab.noise_law.fit import LAW, NoiseLaw, fit_law, likelihood_ratio, profile_interval
from spreadlab.noise_law.leave_one_out import leave_point_out, predictive_check, scored

FREE = {"level": ("a",), "level_g": ("a", "g_ln_hd")}


def held(base: dict, free) -> dict:
    """The base law's coefficients of the terms not in `free` (term -> value)."""
    return {t: float(base[t]) for t in LAW if t not in free}


def refit(cells: pd.DataFrame, base: dict, free=("a",)) -> NoiseLaw:
    """The law of `cells` with the terms of `free` fitted and the others held at `base`.

    Parameters
    ----------
    cells : pandas.DataFrame
        Seed-repeat cells of one target (``cells.seed_cells``).
    base : dict
        The base law's coefficients by term (``fit.LAW``: a, b_ln_n, g_ln_hd).
    free : sequence of str, optional
        The terms fitted (default the level a alone); none: the base law itself.

    Returns
    -------
    NoiseLaw
        The fitted law (``fit.fit_law``), its held terms in ``fixed``.

    Raises
    ------
    ValueError
        If the free terms are not identified by the cells (``fit.fit_law``).
    """
    return fit_law(cells, LAW, held(base, free))


def identified(cells: pd.DataFrame, free) -> bool:
    """Whether leave-one-point-out can refit `free` on these cells: a needs two points, g three
    points at two h/d or more after any one is left out."""
    points = cells.drop_duplicates("point")
    if "g_ln_hd" in free:
        return len(points) >= 3 and all(points.loc[points["point"] != p, "h_over_d"].round(6).nunique() >= 2
                                        for p in points["point"])
    return len(points) >= 2


def factor_by_h_over_d(law: NoiseLaw, base: dict, h_over_d, n: float) -> pd.DataFrame:
    """The law's SD over the base law's at count n and each h/d (the base held fixed), with its
    Wald 95 % interval from the law's covariance."""
    grid = pd.DataFrame({"h_over_d": np.asarray(h_over_d, float), "n": float(n), "mean": 1.0})
    base_sd = refit(grid.assign(s2=1.0, dof=1), base, ()).sd(grid)
    ratio, se = law.sd(grid) / base_sd, law.se_ln_sd(grid)
    return grid.assign(factor=ratio, lo=ratio * np.exp(-1.96 * se), hi=ratio * np.exp(1.96 * se)).drop(columns="mean")


def refit_target(cells: pd.DataFrame, base: dict, base_cells: pd.DataFrame | None = None, variant: str | None = None,
                 boots: int = 2000, h_over_d=(1.1, 1.5, 2.0, 3.0, 4.0, 6.0, 7.5), n_ref: float = 150.0) -> dict:
    """Both refits of one target's cells, their intervals, tests and held-out checks.

    Parameters
    ----------
    cells : pandas.DataFrame
        The scene's seed-repeat cells of one target.
    base : dict
        The base law's coefficients by term.
    base_cells : pandas.DataFrame or None, optional
        The cells the base law was fitted on (the same target): with `variant`, the joint fit of
        both scenes with the scene's indicator ``variant:<variant>``.
    variant : str or None, optional
        The scene's variant name in `cells`.
    boots : int, optional
        Bootstrap resamples of the held-out checks.
    h_over_d : sequence of float, optional
        Where the factor over the base law is tabulated.
    n_ref : float, optional
        The count the factor is tabulated at (it cancels when b is the base's).

    Returns
    -------
    dict
        ``laws`` (free-set name -> NoiseLaw, for the identified ones), ``profile`` (name -> term ->
        (low, high)), ``lr_g_base`` (the test of g = the base's g: stat, df, p; None if level_g is
        not identified), ``level_ratio`` (exp(a - a_base) and its profile interval, base fixed),
        ``joint_ratio`` (the indicator's exp and profile interval, or None), ``factors`` (name ->
        ``factor_by_h_over_d``), ``heldout`` (name -> leave-one-point-out cells) and ``checks``
        (predictor -> ``leave_one_out.predictive_check``: the held-out laws, the base law and the
        stated SDs as they are).
    """
    cells = cells.reset_index(drop=True)
    laws, profile, heldout, checks, factors = {}, {}, {}, {}, {}
    for name, free in FREE.items():
        if not identified(cells, free):
            continue
        law = refit(cells, base, free)
        laws[name] = law
        profile[name] = {t: profile_interval(cells, law, t) for t in law.terms}
        factors[name] = factor_by_h_over_d(law, base, h_over_d, n_ref)
        heldout[name] = leave_point_out(cells, LAW, held(base, free))
        checks[f"{name}, held out"] = predictive_check(heldout[name], boots=boots)
    checks["base law"] = predictive_check(scored(cells.assign(sd_pred=refit(cells, base, ()).sd(cells))), boots=boots)
    checks["stated SDs"] = predictive_check(scored(cells.assign(sd_pred=cells["stated_rms"])), boots=boots)
    a_lo, a_hi = profile["level"]["a"]
    level_ratio = tuple(math.exp(x - base["a"]) for x in (laws["level"].coef[0], a_lo, a_hi))
    joint = None
    if base_cells is not None and variant is not None:
        both = pd.concat([base_cells, cells], ignore_index=True)
        term = f"variant:{variant}"
        fitted = fit_law(both, LAW + (term,))
        lo, hi = profile_interval(both, fitted, term)
        joint = tuple(math.exp(x) for x in (fitted.coefficient(term), lo, hi))
    lr = likelihood_ratio(cells, laws["level_g"], laws["level"]) if "level_g" in laws else None
    return {"laws": laws, "profile": profile, "lr_g_base": lr, "level_ratio": level_ratio, "joint_ratio": joint,
            "factors": factors, "heldout": heldout, "checks": checks}


def config_entry(law: NoiseLaw) -> dict:
    """A target's ``noise_model`` entry of a fitted law.

    Parameters
    ----------
    law : NoiseLaw
        A law with the terms of ``fit.LAW``, fitted or held.

    Returns
    -------
    dict
        ``rel_sd`` (exp(a), 5 decimals), ``n_exponent`` and ``h_over_d_exponent`` (4 decimals), as
        the published config rounds them.
    """
    return {"rel_sd": round(math.exp(law.coefficient("a")), 5), "n_exponent": round(law.coefficient("b_ln_n"), 4),
            "h_over_d_exponent": round(law.coefficient("g_ln_hd"), 4)}

