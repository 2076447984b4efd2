"""Each case's own noise estimate.

Counting noise (SPEC.md, issue 14): across packing seeds the relative SD of MFR and of PD is about
c / sqrt(N), N the spheres' worth of volume measured (passed under the blade in the window for
MFR, in the PD box for PD), c ~ 0.45 in the published fidelity study. The absolute SDs are
c / sqrt(N) x value (one sphere's worth
at least).

Within-case estimate (for comparison): batch means of the flow over equal sub-windows of the blade
travel, from the volume-behind series the scene records every monitor interval (spheres counted
by centre there, so each batch carries up to about a sphere of rounding at its ends besides the
flow's own fluctuation); the SD of the window's MFR is SD(batch MFRs) / sqrt(batches).

c is checked against a table of seeds by ``spreadmap.noise_law.counting``.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .. import targets

if TYPE_CHECKING:
    import pandas as pd

# pandas and scipy.stats are imported where they are used: a case's metrics (scripts/case_metrics.py,
# run once per case) need neither, and importing them costs ~2.5 s per case


def counting_sd(n: float, per_sphere: float, c: float) -> float:
    """Absolute SD of a measure that counts n spheres' worth of volume, each sphere worth
    `per_sphere` of the measure: c sqrt(n) per_sphere, i.e. c / sqrt(n) x value. Below one sphere
    (a jammed case, an empty box) the SD of one sphere's worth, c x per_sphere: a measured zero
    is not exact."""
    if not (math.isfinite(n) and math.isfinite(per_sphere)):
        return math.nan
    return c * math.sqrt(max(n, 1.0)) * abs(per_sphere)


def batch_means_sd(series, x0: float, x1: float, gap: float, width: float, batches: int) -> tuple[float, int]:
    """(SD of the window's MFR from batch means, batches used) from the series of
    [time, blade_rear_x, volume passed] between blade positions x0 and x1. Each batch needs at
    least two monitor intervals of the series; with fewer than 2 such batches: (nan, 0)."""
    arr = np.asarray(series, float).reshape(-1, 3) if len(series) else np.zeros((0, 3))
    x, vol = arr[:, 1], arr[:, 2]
    inside = (x >= x0) & (x <= x1)
    intervals = max(int(np.count_nonzero(inside)) - 1, 0)
    b = min(int(batches), intervals // 2)
    if b < 2 or x1 <= x0 or np.any(np.diff(x) < 0):
        return math.nan, 0
    edges = np.linspace(x0, x1, b + 1)
    v = np.interp(edges, x, vol)
    flows = np.diff(v) / (gap * width * np.diff(edges))
    return float(np.std(flows, ddof=1) / math.sqrt(b)), b


def flow_trend(series, x0: float, x1: float, gap: float, width: float) -> float:
    """Relative change of the flow under the blade between the window's halves, (second -
    first) / mean, from the series of [time, blade_rear_x, volume passed] (linear between its
    points). A steady flow gives 0 within counting noise, whose SD here is 2c / sqrt(N) for N
    spheres passed in the window (each half holds N/2); a pile that runs down gives a negative
    trend. nan when the series does not cover the window."""
    arr = np.asarray(series, float).reshape(-1, 3) if len(series) else np.zeros((0, 3))
    x, vol = arr[:, 1], arr[:, 2]
    if len(x) < 3 or x1 <= x0 or x[0] > x0 or x[-1] < x1 or np.any(np.diff(x) < 0):
        return math.nan
    v0, vm, v1 = np.interp([x0, 0.5 * (x0 + x1), x1], x, vol)
    first, second = vm - v0, v1 - vm
    if first + second <= 0:
        return math.nan
    return float((second - first) / (0.5 * (first + second)))


# The stated noise SDs of a results table (counting law for MFR and PD, block jackknife for the layer):
# spreadmap.targets.sd_columns(), one per registered target


def calibration_factors(table: pd.DataFrame, calibration: list[dict] | None, target: str | None = None) -> np.ndarray:
    """Per row, the factor the stated noise SD of `target` (a target name, e.g. "mfr") is scaled
    by.

    The `factor` of the first region of `calibration` the case lies in that applies to the
    target (a region is h/d from `h_over_d_from`, inclusive, to below `h_over_d_below`, a bound
    left out being open; it applies to the targets it lists under `targets`, to every one if it
    lists none), 1 outside every such region.

    Parameters
    ----------
    table : pandas.DataFrame
        A results table (``h_um`` and ``d_um`` are read).
    calibration : list of dict or None
        The config's `noise_calibration` regions; None or empty: all factors 1.
    target : str or None, optional
        The target name; None: every region applies.

    Returns
    -------
    numpy.ndarray
        One factor (dimensionless) per row of `table`.
    """
    import pandas as pd
    factors = np.ones(len(table))
    if not calibration or table.empty:
        return factors
    h_over_d = (pd.to_numeric(table["h_um"], errors="coerce") / pd.to_numeric(table["d_um"], errors="coerce")).to_numpy(float)
    placed = np.zeros(len(table), dtype=bool)
    for region in calibration:
        if target is not None and region.get("targets") and target not in region["targets"]:
            continue
        below = float(region.get("h_over_d_below", np.inf))
        inside = ~placed & (h_over_d >= float(region.get("h_over_d_from", 0.0))) & (h_over_d < below)
        factors[inside] = float(region["factor"])
        placed |= inside
    return factors


def calibrated_noise(table: pd.DataFrame, calibration: list[dict] | None) -> pd.DataFrame:
    """A copy of a results table whose stated noise SDs (``targets.sd_columns()``) are scaled by region
    where packing-seed repeats measured them off (config `noise_calibration`: at thin gaps the
    flow comes in bursts the counting law does not see). The measured values are left as they
    are; every analysis that weighs cases by their noise (the loop's criteria and model, the
    surrogate, the maps) reads the calibrated SDs."""
    import pandas as pd
    out = table.copy()
    for t in targets.REGISTRY.values():
        if t.sd_column in out.columns:
            out[t.sd_column] = (pd.to_numeric(out[t.sd_column], errors="coerce")
                                * calibration_factors(out, calibration, t.name))
    return out
