"""Synthetic results tables with a known truth and known noise, for the surrogate and map tests.

``truth_mfr`` is shaped like the DEM's mass flow rate (nothing passes a gap near one diameter,
a saturating rise with h/d, less with friction, a little less with speed); ``truth_pd`` follows it
as mass conservation makes the DEM's PD do. The noise of a case is the counting noise of the
spheres that pass, relative SD ``rel`` at the design's median count (0.45 / sqrt(N) in the DEM).
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.stats import qmc

from spreadmap.design import NAMES, to_physical


def truth_mfr(X):
    f, d, h, v = np.asarray(X, float).T
    return 0.62 * (1 - np.exp(-(h / d - 0.9) / 1.2)) * (1 - 0.5 * (f - 0.15)) * (1 - 0.01 * (v - 5))


def truth_pd(X):
    f, d, h, v = np.asarray(X, float).T
    return 0.95 * truth_mfr(X) + 0.02 * (h - 55) / 20 - 0.03 * (f - 0.15) / 0.3


TRUTH = {"mfr": truth_mfr, "pd": truth_pd}


def noise_sd(X, target, rel):
    """Absolute noise SD: ``rel`` x the value, larger where fewer spheres pass (small h/d)."""
    f, d, h, v = np.asarray(X, float).T
    y = TRUTH[target](X)
    count = np.clip(76 * truth_mfr(X) * h / d, 5, None)
    return rel * np.abs(y) * np.sqrt(np.median(count) / count)


def halton_points(n, seed=42):
    return to_physical(qmc.Halton(d=4, scramble=True, seed=seed).random(n))


def table(n=64, rel=0.07, seed=0, with_sd=True, points=None):
    """A results table of n scrambled Halton cases with noisy MFR and PD (and their SD columns)."""
    X = halton_points(n) if points is None else points
    rng = np.random.default_rng(seed)
    df = pd.DataFrame(X, columns=list(NAMES))
    df.insert(0, "index", np.arange(len(X)))
    df.insert(0, "sweep", "lds")
    df.insert(0, "case_id", [f"lds-{i:05d}" for i in range(len(X))])
    df["status"], df["flagged"], df["regime"] = "ok", False, "normal"
    for t in TRUTH:
        sd = noise_sd(X, t, rel)
        df[t] = TRUTH[t](X) + rng.normal(0, sd)
        if with_sd:
            df[f"{t}_sd"] = sd
    return df


def fresh(model_targets, n=2000, rel=0.07, seed=99):
    """Fresh uniform points with fresh noisy draws: the truth a validation must predict."""
    rng = np.random.default_rng(seed)
    X = to_physical(rng.random((n, 4)))
    return X, {t: TRUTH[t](X) + rng.normal(0, noise_sd(X, t, rel)) for t in model_targets}
