"""Sobol indices over draws of the surrogate, and the noise share of a single run's variance.

One scrambled Sobol sample (A, B and the d matrices AB_i, ``n`` rows each); the draw source gives
``draws`` joint draws of each target's mean function on all of it (GP posterior samples, or MLP
members). Every draw is paired with its own bootstrap resample of the n rows, so the spread of
the indices over the draws carries both the surrogate's uncertainty and the Monte Carlo error of
the finite sample. ``scipy.stats.sobol_indices`` (Saltelli 2010 estimators) computes the indices
of all draws in one call. The point estimate is that of the mean function on the full sample.

Noise share: noise variance of one run (mean over A) over that plus the variance of the mean
function over the design space: the part of a single DEM run's spread no parameter explains.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats
from scipy.stats import qmc

from ..design import NAMES, Design


def _indices(fA, fB, fAB, n):
    res = stats.sobol_indices(func={"f_A": fA, "f_B": fB, "f_AB": fAB}, n=n)
    return np.atleast_2d(res.first_order), np.atleast_2d(res.total_order)


def sobol_draws(source, targets, n: int = 256, draws: int = 64, ranges=None, seed: int = 0):
    """Per target: point estimates and per-draw S1, ST (draws, 4), and the noise share.

    Returns (table, per_draw): table has one row per (target, parameter) with S1, S1_low, S1_high,
    ST, ST_low, ST_high (95 % percentile intervals over the draws), noise_share, noise_share_low,
    noise_share_high; per_draw = {target: {"S1": (draws, 4), "ST": (draws, 4)}}.
    """
    if n < 2 or n & (n - 1):
        raise ValueError(f"n must be a power of 2, got {n}")
    design = Design.of(ranges)
    d = len(NAMES)
    U = qmc.Sobol(2 * d, scramble=True, seed=seed).random(n)
    A, B = design.to_physical(U[:, :d]), design.to_physical(U[:, d:])
    AB = []
    for i in range(d):
        m = A.copy()
        m[:, i] = B[:, i]
        AB.append(m)
    X = np.vstack([A, B, *AB])
    F = source.draws(X, draws, seed=seed, targets=list(targets))
    stats_all = source.predict_stats(X)
    rng = np.random.default_rng([seed, 11])
    rows = rng.integers(0, n, (draws, n))
    table, per_draw = [], {}
    for t in targets:
        mean = stats_all[t][0]
        s1_hat, st_hat = _indices(mean[None, :n], mean[None, n:2 * n],
                                  mean[2 * n:].reshape(d, 1, n), n)
        Ft = F[t]
        fA = np.take_along_axis(Ft[:, :n], rows, axis=1)
        fB = np.take_along_axis(Ft[:, n:2 * n], rows, axis=1)
        fAB = np.stack([np.take_along_axis(Ft[:, (2 + i) * n:(3 + i) * n], rows, axis=1) for i in range(d)])
        with np.errstate(invalid="ignore", divide="ignore"):
            s1, st = _indices(fA, fB, fAB, n)
        per_draw[t] = {"S1": s1, "ST": st}
        noise_var = float(np.mean(stats_all[t][2][:n] ** 2 - stats_all[t][1][:n] ** 2))
        fvar = Ft[:, :n].var(axis=1, ddof=1)
        share = noise_var / (noise_var + fvar) if noise_var > 0 else np.zeros(draws)
        share_hat = noise_var / (noise_var + mean[:n].var(ddof=1)) if noise_var > 0 else 0.0
        for i, p in enumerate(NAMES):
            table.append({
                "target": t, "parameter": p,
                "S1": s1_hat[0, i], "S1_low": np.nanquantile(s1[:, i], 0.025), "S1_high": np.nanquantile(s1[:, i], 0.975),
                "ST": st_hat[0, i], "ST_low": np.nanquantile(st[:, i], 0.025), "ST_high": np.nanquantile(st[:, i], 0.975),
                "noise_share": share_hat, "noise_share_low": float(np.quantile(share, 0.025)),
                "noise_share_high": float(np.quantile(share, 0.975)), "n": n, "draws": draws})
    return pd.DataFrame(table), per_draw
