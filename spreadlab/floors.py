"""The numbers behind the two floors' comparison: one map model per floor, their ratio and difference.

Each floor's main job leaves its own map model (results/surrogate/model.joblib, fitted on that floor's
cases). At a design point each model gives the mean of a target and the model SD of that mean (what
its posterior does not know; not the noise of one run). The two floors' cases are independent, so the
two posteriors are too, and at one point

    ratio = mean on floor A / mean on floor B,    difference = mean on A - mean on B.

The difference is normal: its SD is sqrt(sd_A^2 + sd_B^2). The ratio of two independent normals
has no closed-form quantiles, but while floor B's mean is positive its CDF has one:

    P(A / B <= r) = P(A - r B <= 0) = Phi((r m_B - m_A) / sqrt(sd_A^2 + r^2 sd_B^2)),

so the ratio's quantiles are the roots of that in r (the limits of Fieller's interval). They are found by
bisection here; where floor B's own interval reaches `min_value` (a mean that may be nothing, a
jammed flow) the ratio is not defined and is reported as NaN with ``<t>_ratio_defined`` false.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from spreadmap.design import NAMES, Design, h_over_d
from spreadmap.table import flagged as table_flagged
from spreadmap.table import usable_cases


def ratio_quantile(m_a, s_a, m_b, s_b, q: float, lo: float = 1e-3, hi: float = 1e3, iterations: int = 80) -> np.ndarray:
    """The q-quantile of A / B, A ~ N(m_a, s_a^2) and B ~ N(m_b, s_b^2) independent, B > 0 assumed:
    the r at which Phi((r m_b - m_a) / sqrt(s_a^2 + r^2 s_b^2)) = q, by bisection on [lo, hi] (the CDF
    rises in r while m_b > 0). Arrays broadcast."""
    m_a, s_a, m_b, s_b = np.broadcast_arrays(*(np.asarray(x, float) for x in (m_a, s_a, m_b, s_b)))
    z = stats.norm.ppf(q)
    low, high = np.full(m_a.shape, lo), np.full(m_a.shape, hi)
    for _ in range(iterations):
        mid = np.sqrt(low * high)  # the ratio is positive here: bisect on its logarithm
        below = (mid * m_b - m_a) / np.sqrt(s_a**2 + mid**2 * s_b**2) < z
        low, high = np.where(below, mid, low), np.where(below, high, mid)
    return np.sqrt(low * high)


def compare(model_a, model_b, frame: pd.DataFrame, targets, level: float = 0.95, min_value: float = 0.02) -> pd.DataFrame:
    """Per point of ``frame`` and target: both floors' means and model SDs, their difference and their ratio.

    See the module docstring for the difference's interval and the ratio's quantiles (Fieller).

    Parameters
    ----------
    model_a, model_b : spreadmap.surrogate.saved_model.SurrogateModel
        The map models of floor A and floor B (each floor's results/surrogate/model.joblib); their
        ``predict_stats`` give the mean and the model SD of each target.
    frame : pandas.DataFrame
        The points: columns NAMES (f [-], d_um [um], h_um [um], v_mm_s [mm/s]).
    targets : sequence of str
        The targets compared (targets of both models).
    level : float, optional
        The level of the intervals, in (0, 1).
    min_value : float, optional
        The ratio is defined only where floor B's lower bound at ``level`` lies above this (the
        targets are dimensionless).

    Returns
    -------
    pandas.DataFrame
        Per point: NAMES, ``h_over_d``, and per target ``<t>_a``, ``<t>_a_sd``, ``<t>_b``,
        ``<t>_b_sd`` (means and model SDs on each floor), ``<t>_diff`` with ``_lo``/``_hi`` (the
        interval at ``level``), ``<t>_ratio`` (median) with ``_lo``/``_hi`` (NaN where not
        defined), and ``<t>_ratio_defined``: floor B's lower bound at ``level`` above
        ``min_value`` and floor A's mean positive.
    """
    X = frame[list(NAMES)].to_numpy(float)
    out = frame[list(NAMES)].copy()
    out["h_over_d"] = h_over_d(X)
    a_stats, b_stats = model_a.predict_stats(X), model_b.predict_stats(X)
    z = stats.norm.ppf(0.5 + level / 2.0)
    for t in targets:
        m_a, s_a = a_stats[t][0], a_stats[t][1]
        m_b, s_b = b_stats[t][0], b_stats[t][1]
        out[f"{t}_a"], out[f"{t}_a_sd"], out[f"{t}_b"], out[f"{t}_b_sd"] = m_a, s_a, m_b, s_b
        diff, diff_sd = m_a - m_b, np.hypot(s_a, s_b)
        out[f"{t}_diff"], out[f"{t}_diff_lo"], out[f"{t}_diff_hi"] = diff, diff - z * diff_sd, diff + z * diff_sd
        defined = (m_b - z * s_b > min_value) & (m_a > 0)
        q = [ratio_quantile(m_a, s_a, m_b, s_b, p) for p in (0.5 - level / 2.0, 0.5, 0.5 + level / 2.0)]
        for name, value in zip(("_ratio_lo", "_ratio", "_ratio_hi"), q):
            out[f"{t}{name}"] = np.where(defined, value, np.nan)
        out[f"{t}_ratio_defined"] = defined
    return out


def box_sample(n: int, seed: int = 0, ranges=None) -> pd.DataFrame:
    """n scrambled-Sobol' points over the design box (scipy.stats.qmc; n a power of 2).

    Parameters
    ----------
    n : int
        How many points (a power of 2 keeps the Sobol' sequence balanced).
    seed : int, optional
        The scrambling seed.
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.

    Returns
    -------
    pandas.DataFrame
        Columns NAMES (f [-], d_um [um], h_um [um], v_mm_s [mm/s]), one row per point.
    """
    from scipy.stats import qmc

    u = qmc.Sobol(len(NAMES), scramble=True, seed=seed).random(n)
    return pd.DataFrame(Design.of(ranges).to_physical(u), columns=list(NAMES))


def by_band(table: pd.DataFrame, target: str, edges=(1.0, 1.5, 2.0, 3.0, 5.0, 8.0)) -> pd.DataFrame:
    """The ratio's spread over the box per h/d band.

    Per band: the points, how many have the ratio defined, the median of the points' median ratios
    and their range, and the median of the points' interval widths.

    Parameters
    ----------
    table : pandas.DataFrame
        ``compare``'s table over the box (``h_over_d`` and the target's columns).
    target : str
        The target.
    edges : sequence of float, optional
        The band edges in h/d [-]; a band holds ``from <= h/d < below``.

    Returns
    -------
    pandas.DataFrame
        One row per band: ``h_over_d_from``, ``h_over_d_below``, ``points``, ``ratio_defined``
        (points with the ratio defined), ``ratio_median``, ``ratio_min``, ``ratio_max`` (over
        those points), ``interval_width_median`` (of ``_ratio_hi - _ratio_lo``) and
        ``diff_median`` (the median difference over all the band's points); NaN where no point
        counts.
    """
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        part = table[(table["h_over_d"] >= lo) & (table["h_over_d"] < hi)]
        ok = part[part[f"{target}_ratio_defined"]]
        rows.append({"h_over_d_from": lo, "h_over_d_below": hi, "points": len(part),
                     "ratio_defined": len(ok),
                     "ratio_median": float(ok[f"{target}_ratio"].median()) if len(ok) else np.nan,
                     "ratio_min": float(ok[f"{target}_ratio"].min()) if len(ok) else np.nan,
                     "ratio_max": float(ok[f"{target}_ratio"].max()) if len(ok) else np.nan,
                     "interval_width_median": float((ok[f"{target}_ratio_hi"] - ok[f"{target}_ratio_lo"]).median())
                     if len(ok) else np.nan,
                     "diff_median": float(part[f"{target}_diff"].median()) if len(part) else np.nan})
    return pd.DataFrame(rows)


def piles_by_band(cases: pd.DataFrame, min_heap_h2: float, edges=(1.0, 1.5, 2.0, 3.0, 5.0, 8.0)) -> pd.DataFrame:
    """A floor's sweep read for drained piles, per h/d band (issue 36).

    Per band: cases, finished, flagged; of the flagged, those whose pile ran down (less than
    `min_heap_h2` h^2 ahead of the blade at the window's end, or no heap measured) and those whose
    flow was unsteady with the heap full; spheres rolled off the floor's ends (median, max, median
    share of the case's spheres); the heap at the window's end in h^2 (min, median); median MFR of
    the usable cases. Rows of every band, empty ones with zero cases.

    Parameters
    ----------
    cases : pandas.DataFrame
        A cases table (results table): ``h_um``, ``d_um``, ``status``, ``flagged``,
        ``heap_end_h2``, ``rolled_off_particles``, ``n_particles``, ``mfr``.
    min_heap_h2 : float
        The run-down bound [h^2] (config ``stability.min_heap_h2``).
    edges : sequence of float, optional
        The band edges in h/d [-]; a band holds ``from <= h/d < below``.

    Returns
    -------
    pandas.DataFrame
        One row per band: ``h_over_d_from``, ``h_over_d_below``, ``cases``, ``finished`` (status
        ok), ``flagged`` (of the finished), ``flagged_ran_down``, ``flagged_unsteady_heap_full``,
        ``rolled_off_median``, ``rolled_off_max``, ``rolled_off_share_median``, ``heap_end_h2_min``,
        ``heap_end_h2_median`` [h^2] and ``mfr_median`` (of the usable cases: finished, not
        flagged); NaN where no case counts.
    """
    hd = pd.Series(h_over_d(cases), index=cases.index)
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        part = cases[(hd >= lo) & (hd < hi)]
        ok = part[part["status"] == "ok"]
        flagged = ok[table_flagged(ok)]
        heap = ok["heap_end_h2"]
        ran_down = flagged["heap_end_h2"].isna() | (flagged["heap_end_h2"] < min_heap_h2)
        usable = usable_cases(part)
        rolled = ok["rolled_off_particles"]
        rows.append({"h_over_d_from": lo, "h_over_d_below": hi, "cases": len(part), "finished": len(ok),
                     "flagged": len(flagged), "flagged_ran_down": int(ran_down.sum()),
                     "flagged_unsteady_heap_full": int((~ran_down).sum()),
                     "rolled_off_median": float(rolled.median()) if len(ok) else np.nan,
                     "rolled_off_max": float(rolled.max()) if len(ok) else np.nan,
                     "rolled_off_share_median": float((rolled / ok["n_particles"]).median()) if len(ok) else np.nan,
                     "heap_end_h2_min": float(heap.min()) if len(ok) else np.nan,
                     "heap_end_h2_median": float(heap.median()) if len(ok) else np.nan,
                     "mfr_median": float(usable["mfr"].median()) if len(usable) else np.nan})
    return pd.DataFrame(rows)
