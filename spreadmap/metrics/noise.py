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

Steady flow (issue: the steady-window flag): the change of the flow between the window's halves in
SEs of that within-window noise (``flow_trend_batch_z``), a standard-normal score whatever the
number of batches, so that one bound reads the same tail probability everywhere.

c is checked against a table of seeds by ``spreadlab.noise_law.counting``.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy import special

from .. import targets
from ..design import h_over_d

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


# fewest batches the flow-trend z is defined on: its noise has batches - 4 degrees of freedom
TREND_MIN_BATCHES = 6


def t_normal_score(t: float, dof: int) -> float:
    """The standard-normal score of a Student-t statistic with `dof` degrees of freedom: the z
    whose normal tail probability is the t's, sign kept (P(T > t) = P(Z > z)). A t from a noise
    estimate of few degrees of freedom has heavy tails; its score does not, so |z| > 3 is the
    normal's 0.27 % whatever `dof`.

    Parameters
    ----------
    t : float
        The t statistic.
    dof : int
        Its degrees of freedom (1 or more).

    Returns
    -------
    float
        The normal score (dimensionless); +-inf for an infinite t, nan for nan or dof < 1.
    """
    if math.isnan(t) or dof < 1:
        return math.nan
    # the t's upper tail, then the normal's inverse tail, both accurate far out: the functions
    # scipy.stats.t.sf and norm.isf call (stdtr(dof, -t) and -ndtri(p); the same to the bit over 140,000
    # draws), from scipy.special, which every Snakemake start imports in 0.1 s, not scipy.stats' 0.6 s
    return math.copysign(float(-special.ndtri(special.stdtr(dof, -abs(t)))), t)


def flow_trend_batch_z(series, x0: float, x1: float, batches: int) -> tuple[float, int]:
    """The flow's change between the window's halves in SEs of its own within-window noise, as a
    standard-normal score, and the batches it used: (z, b).

    The window [x0, x1] of blade travel is cut into b batches (the largest even number up to
    `batches` with at least two monitor intervals of the series in each; b >= TREND_MIN_BATCHES)
    at the series' own points nearest to b equal parts, so that no batch shares an interpolated
    volume with its neighbour (interpolated edges make neighbours correlate: the z's SD was
    1.03-1.06 on a steady Poisson flow). Batch i passes volume v_i over travel l_i; its flow is
    f_i = v_i / l_i, of variance s^2 / l_i for a noise of s^2 per unit travel. The halves' flows
    are F1 = (sum of v_i) / L1 over the first b/2 batches and F2 likewise (the halves of
    ``flow_trend``, to within half a monitor interval), and D = F2 - F1 has
    SE(D) = s sqrt(1/L1 + 1/L2) (2 s_batch / sqrt(b) for b equal batches, s_batch the SD of one
    batch's flow).

    s is estimated from the batches' scatter about a quadratic in travel plus a jump at the
    window's middle (weighted least squares, weights l_i; 4 parameters, b - 4 degrees of freedom).
    The jump and the slope must be in that curve: the plain SD of the batches holds the trend
    itself (a difference D adds b D^2 / 4 to their sum of squares), so D / (2 SD / sqrt(b)) can
    never exceed sqrt(b - 1) (2.65 at 8 batches) and a bound of 3 would never fire; the scatter
    about the halves' own means misses a ramp (a noiseless one reads z 2.8 at 8 batches). D lies in
    the curve's span, so it is independent of the residuals and t = D / SE follows Student's t
    with b - 4 degrees of freedom for normal, independent batches, whatever quadratic-plus-jump
    course the mean flow takes. z is t's normal score (``t_normal_score``): standard normal for a
    steady flow, so a bound reads the same tail probability at any b.

    Parameters
    ----------
    series : sequence of [time, blade_rear_x, volume passed]
        The scene's volume-behind series (spheres counted by centre), x non-decreasing.
    x0, x1 : float
        The window's blade positions [m].
    batches : int
        The most batches to use (config ``metrics.within_batches``).

    Returns
    -------
    (float, int)
        z (dimensionless; > 0: the flow rose; +-inf: a change without any noise) and b; (nan, 0)
        when the series does not cover the window or has too few points for TREND_MIN_BATCHES
        batches.
    """
    arr = np.asarray(series, float).reshape(-1, 3) if len(series) else np.zeros((0, 3))
    x, vol = arr[:, 1], arr[:, 2]
    if len(x) < 3 or x1 <= x0 or x[0] > x0 or x[-1] < x1 or np.any(np.diff(x) < 0):
        return math.nan, 0
    inside = (x > x0) & (x < x1)
    nodes = np.concatenate([[x0], x[inside], [x1]])  # the window's ends, interpolated, and the series' points
    volume = np.concatenate([np.interp([x0], x, vol), vol[inside], np.interp([x1], x, vol)])
    keep = np.concatenate([[True], np.diff(nodes) > 0])  # repeated points (a blade at rest) once
    nodes, volume = nodes[keep], volume[keep]
    intervals = len(nodes) - 1
    for b in range(min(int(batches), intervals // 2) // 2 * 2, TREND_MIN_BATCHES - 1, -2):
        cuts = np.unique(np.abs(nodes[:, None] - np.linspace(x0, x1, b + 1)[None, :]).argmin(axis=0))
        if len(cuts) == b + 1 and np.all(np.diff(cuts) >= 2):
            break
    else:
        return math.nan, 0
    length, passed = np.diff(nodes[cuts]), np.diff(volume[cuts])
    flows, w = passed / length, np.sqrt(length)
    u = (0.5 * (nodes[cuts][1:] + nodes[cuts][:-1]) - 0.5 * (x0 + x1)) / (x1 - x0)
    design = np.column_stack([np.ones(b), np.arange(b) >= b // 2, u, u * u])
    q, _ = np.linalg.qr(design * w[:, None])
    resid = w * flows - q @ (q.T @ (w * flows))
    first, second = slice(0, b // 2), slice(b // 2, b)
    l1, l2 = length[first].sum(), length[second].sum()
    diff = float(passed[second].sum() / l2 - passed[first].sum() / l1)
    se = math.sqrt(float(resid @ resid) / (b - 4) * (1.0 / l1 + 1.0 / l2))
    scale = float(passed.sum() / (l1 + l2))
    if se <= 1e-12 * abs(scale):  # no noise at all (a synthetic series)
        return (0.0 if abs(diff) <= 1e-12 * abs(scale) else math.copysign(math.inf, diff)), b
    return t_normal_score(diff / se, b - 4), b


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
    factors = np.ones(len(table))
    if not calibration or table.empty:
        return factors
    ratio = h_over_d(table)
    placed = np.zeros(len(table), dtype=bool)
    for region in calibration:
        if target is not None and region.get("targets") and target not in region["targets"]:
            continue
        below = float(region.get("h_over_d_below", np.inf))
        inside = ~placed & (ratio >= float(region.get("h_over_d_from", 0.0))) & (ratio < below)
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
