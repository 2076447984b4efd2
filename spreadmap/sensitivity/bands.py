"""Band widths (the study's measure, read off the maps) over draws of the surrogate.

Sweep one parameter over its whole range while the others stay at the centre of the design
space; the band width is the spread max - min of a target along the sweep, in the target's units.
Computed on the mean function (the point estimate) and on each joint draw (its interval).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..design import NAMES, Design


def band_widths(source, targets, n_sweep: int = 21, draws: int = 64, ranges=None, seed: int = 0):
    """(table, per_draw): rows (target, parameter) with band, band_low, band_high (95 % over
    the draws); per_draw = {target: (draws, 4) widths}."""
    if n_sweep < 2:
        raise ValueError("n_sweep must be at least 2")
    design = Design.of(ranges)
    low, high = design.bounds()
    centre = (low + high) / 2
    pts = []
    for i in range(len(NAMES)):
        p = np.repeat(centre[None, :], n_sweep, axis=0)
        p[:, i] = design.axis(NAMES[i], n_sweep)
        pts.append(p)
    X = np.vstack(pts)
    F = source.draws(X, draws, seed=seed + 1, targets=list(targets))
    mean = source.predict_stats(X)
    rows, per_draw = [], {}
    for t in targets:
        m = mean[t][0].reshape(len(NAMES), n_sweep)
        f = F[t].reshape(draws, len(NAMES), n_sweep)
        w = f.max(axis=2) - f.min(axis=2)
        per_draw[t] = w
        for i, p in enumerate(NAMES):
            rows.append({"target": t, "parameter": p, "low": low[i], "high": high[i],
                         "band": float(np.ptp(m[i])), "band_low": float(np.quantile(w[:, i], 0.025)),
                         "band_high": float(np.quantile(w[:, i], 0.975))})
    return pd.DataFrame(rows), per_draw
