"""Rank the four design parameters by their influence on MFR and PD.

Two methods, both applied to a predictor (the surrogate, or any callable
``predict(points[n, 4]) -> [n, 2]`` with columns mfr, pd, points in physical units, NAMES order):

* **Band width** (the study's method, read off the maps): sweep one parameter over its whole
  range while the other three stay at a base point, and take the spread ``max - min`` of each
  target along the sweep.  With several base points the spread is averaged over them (the
  spread at each base point is also kept, as its standard deviation and maximum).  The band
  width is in the units of the target (both targets are dimensionless volume fractions), so
  it tells directly how far a parameter can move MFR or PD on a map.
* **Variance-based** (Sobol'): first-order (S1) and total (ST) indices of each target with every
  parameter uniform over its range, estimated by ``scipy.stats.sobol_indices`` (Saltelli 2010
  estimators on a scrambled Sobol' sample) with BCa bootstrap confidence intervals from its
  ``.bootstrap()``.  S1 is the share of the target's variance explained by the parameter alone,
  ST the share it is involved in, interactions included; ST - S1 measures interactions.

``ranking_table`` joins both per target into one CSV-ready table.

Costs: band width needs ``n_base * 4 * n_sweep`` predictions.  Sobol' needs ``6 n`` predictions
(cheap for the surrogate), but the BCa bootstrap runs a jackknife over the n samples, so its cost
grows as n^2: about 0.5 s at n = 1024, 4 s at 4096, 17 s at 8192 and 100 s at 16384 (2 cores).
"""
from __future__ import annotations

import warnings
from typing import Callable, Sequence

import numpy as np
import pandas as pd
from scipy import stats

from spreadmap.design import NAMES, TARGETS, bounds

Predictor = Callable[[np.ndarray], np.ndarray]

__all__ = [
    "band_widths",
    "sobol_table",
    "ranking_table",
    "sensitivity",
    "plot_ranking",
]


def _predict(predict: Predictor, points: np.ndarray, n_targets: int) -> np.ndarray:
    out = np.asarray(predict(np.asarray(points, float)), float)
    if out.ndim == 1:
        out = out[:, None]
    if out.shape != (len(points), n_targets):
        raise ValueError(
            f"predictor returned shape {out.shape}, expected ({len(points)}, {n_targets})"
        )
    return out


def _rank(values: pd.Series) -> pd.Series:
    """Rank 1 = most influential (largest value); ties share the smaller rank."""
    return values.rank(ascending=False, method="min").astype(int)


def band_widths(
    predict: Predictor,
    base_points: np.ndarray | Sequence[float] | None = None,
    ranges: dict | None = None,
    n_sweep: int = 41,
    targets: Sequence[str] = TARGETS,
    names: Sequence[str] = NAMES,
) -> tuple[pd.DataFrame, dict[str, list[str]]]:
    """Band width of each target caused by sweeping each parameter over its range.

    Parameters
    ----------
    predict : predictor, physical units, NAMES order.
    base_points : the values at which the other parameters are held, shape (4,) or (m, 4) in
        physical units.  None: the centre of the design space.  With m > 1 base points the band
        width is the mean over them.
    ranges : config ranges overriding the design defaults (see ``design.bounds``).
    n_sweep : points along each sweep, end points included.

    Returns
    -------
    table : one row per parameter: ``parameter``, ``low``, ``high`` (the swept range), and per
        target ``<t>_band`` (mean spread over the base points), ``<t>_band_std``,
        ``<t>_band_max`` and ``<t>_rank`` (1 = widest band).
    ranking : ``{target: [parameters, widest band first]}``.
    """
    low, high = bounds(ranges)
    names = list(names)
    targets = list(targets)
    if base_points is None:
        base = ((low + high) / 2.0)[None, :]
    else:
        base = np.atleast_2d(np.asarray(base_points, float))
    if base.shape[1] != len(names):
        raise ValueError(f"base points need {len(names)} columns, got {base.shape[1]}")
    if n_sweep < 2:
        raise ValueError("n_sweep must be at least 2")

    m = len(base)
    rows = []
    for i, name in enumerate(names):
        sweep = np.linspace(low[i], high[i], n_sweep)
        pts = np.repeat(base, n_sweep, axis=0)  # base 0 sweep, base 1 sweep, ...
        pts[:, i] = np.tile(sweep, m)
        y = _predict(predict, pts, len(targets)).reshape(m, n_sweep, len(targets))
        spread = y.max(axis=1) - y.min(axis=1)  # (m, targets)
        row = {"parameter": name, "low": low[i], "high": high[i]}
        for k, t in enumerate(targets):
            row[f"{t}_band"] = spread[:, k].mean()
            row[f"{t}_band_std"] = spread[:, k].std(ddof=1) if m > 1 else 0.0
            row[f"{t}_band_max"] = spread[:, k].max()
        rows.append(row)
    table = pd.DataFrame(rows)
    ranking = {}
    for t in targets:
        table[f"{t}_rank"] = _rank(table[f"{t}_band"])
        ranking[t] = list(table.sort_values([f"{t}_rank", "parameter"])["parameter"])
    return table, ranking


def _ci(boot_result, estimate: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray]:
    """Confidence bounds of a bootstrap result; where BCa is undefined (a degenerate bootstrap
    distribution, e.g. an input with no effect at all, whose index is exactly 0 in every
    resample) fall back to the percentile interval of the bootstrap distribution."""
    lo = np.array(boot_result.confidence_interval.low, float)
    hi = np.array(boot_result.confidence_interval.high, float)
    bad = ~(np.isfinite(lo) & np.isfinite(hi))
    if bad.any():
        dist = np.asarray(boot_result.bootstrap_distribution, float)  # (s, d, n_resamples)
        alpha = (1.0 - level) / 2.0
        plo = np.nanquantile(dist, alpha, axis=-1)
        phi = np.nanquantile(dist, 1.0 - alpha, axis=-1)
        lo = np.where(bad, plo, lo)
        hi = np.where(bad, phi, hi)
        still = ~(np.isfinite(lo) & np.isfinite(hi))
        lo = np.where(still, estimate, lo)
        hi = np.where(still, estimate, hi)
    return lo, hi


def sobol_table(
    predict: Predictor,
    n: int = 4096,
    ranges: dict | None = None,
    seed: int | None = 0,
    confidence_level: float = 0.95,
    n_resamples: int = 999,
    targets: Sequence[str] = TARGETS,
    names: Sequence[str] = NAMES,
) -> pd.DataFrame:
    """First-order and total Sobol' indices of each target, with bootstrap confidence intervals.

    Every parameter is uniform over its range (``design.bounds(ranges)``).  ``n`` is the size of
    scipy's A and B matrices and must be a power of 2; the predictor is called once on
    ``n * (4 + 2)`` points.  ``n_resamples = 0`` skips the bootstrap (CI columns are NaN).
    ``seed`` fixes both the Sobol' sample and the bootstrap resampling (None: fresh entropy).

    Returns a long table, one row per (target, parameter): ``target``, ``parameter``, ``S1``,
    ``S1_ci_low``, ``S1_ci_high``, ``ST``, ``ST_ci_low``, ``ST_ci_high``, ``n``,
    ``confidence_level``.  Small negative indices are estimator noise and are kept as computed.
    """
    if n < 2 or n & (n - 1):
        raise ValueError(f"n must be a power of 2, got {n}")
    low, high = bounds(ranges)
    names = list(names)
    targets = list(targets)
    dists = [stats.uniform(loc=lo, scale=hi - lo) for lo, hi in zip(low, high)]

    def func(x: np.ndarray) -> np.ndarray:  # scipy passes (d, n), wants (s, n)
        return _predict(predict, x.T, len(targets)).T

    res = stats.sobol_indices(func=func, n=n, dists=dists, rng=seed)
    s1 = np.atleast_2d(res.first_order)  # (s, d)
    st = np.atleast_2d(res.total_order)
    nan = np.full_like(s1, np.nan)
    s1_lo = s1_hi = st_lo = st_hi = nan
    if n_resamples:
        # SobolResult.bootstrap takes no rng and draws from numpy's global RandomState: seed it
        # for reproducible intervals, and put the caller's global state back afterwards.
        state = np.random.get_state()
        try:
            if seed is not None:
                np.random.seed(np.random.SeedSequence(seed).generate_state(1)[0])
            with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
                # BCa warns (and returns NaN) for indices whose bootstrap distribution is
                # constant, e.g. an input with no effect at all
                warnings.simplefilter("ignore", RuntimeWarning)
                warnings.simplefilter("ignore",
                                      getattr(stats, "DegenerateDataWarning", RuntimeWarning))
                boot = res.bootstrap(confidence_level=confidence_level,
                                     n_resamples=n_resamples)
        finally:
            np.random.set_state(state)
        s1_lo, s1_hi = (np.atleast_2d(a) for a in _ci(boot.first_order, s1, confidence_level))
        st_lo, st_hi = (np.atleast_2d(a) for a in _ci(boot.total_order, st, confidence_level))

    rows = []
    for k, t in enumerate(targets):
        for i, name in enumerate(names):
            rows.append({
                "target": t, "parameter": name,
                "S1": s1[k, i], "S1_ci_low": s1_lo[k, i], "S1_ci_high": s1_hi[k, i],
                "ST": st[k, i], "ST_ci_low": st_lo[k, i], "ST_ci_high": st_hi[k, i],
                "n": n, "confidence_level": confidence_level,
            })
    return pd.DataFrame(rows)


def ranking_table(band: pd.DataFrame, sobol: pd.DataFrame) -> pd.DataFrame:
    """Join the band-width table and the Sobol' table: one row per (target, parameter).

    Columns: ``target``, ``parameter``, ``band_width``, ``rank_band``, ``S1``, ``S1_ci_low``,
    ``S1_ci_high``, ``ST``, ``ST_ci_low``, ``ST_ci_high``, ``rank_ST`` (1 = most influential),
    ``ranks_agree``.  Rows are sorted by target, then by rank by ST.
    """
    parts = []
    for t, sob in sobol.groupby("target", sort=False):
        if f"{t}_band" not in band:
            raise KeyError(f"band-width table has no column {t}_band")
        b = band[["parameter", f"{t}_band"]].rename(columns={f"{t}_band": "band_width"})
        b["rank_band"] = _rank(b["band_width"])
        s = sob[["target", "parameter", "S1", "S1_ci_low", "S1_ci_high",
                 "ST", "ST_ci_low", "ST_ci_high"]].copy()
        s["rank_ST"] = _rank(s["ST"])
        merged = s.merge(b, on="parameter", how="outer", validate="one_to_one")
        merged["target"] = t
        parts.append(merged)
    table = pd.concat(parts, ignore_index=True)
    table["ranks_agree"] = table["rank_band"] == table["rank_ST"]
    cols = ["target", "parameter", "band_width", "rank_band", "S1", "S1_ci_low", "S1_ci_high",
            "ST", "ST_ci_low", "ST_ci_high", "rank_ST", "ranks_agree"]
    order = {t: i for i, t in enumerate(dict.fromkeys(sobol["target"]))}
    table = table[cols].sort_values(
        ["target", "rank_ST", "parameter"], key=lambda c: c.map(order) if c.name == "target" else c
    )
    return table.reset_index(drop=True)


def sensitivity(
    predict: Predictor,
    n: int = 4096,
    base_points: np.ndarray | Sequence[float] | None = None,
    ranges: dict | None = None,
    n_sweep: int = 41,
    seed: int | None = 0,
    confidence_level: float = 0.95,
    n_resamples: int = 999,
) -> pd.DataFrame:
    """Both methods on one predictor; returns ``ranking_table`` (write it with ``to_csv``)."""
    band, _ = band_widths(predict, base_points=base_points, ranges=ranges, n_sweep=n_sweep)
    sob = sobol_table(predict, n=n, ranges=ranges, seed=seed,
                      confidence_level=confidence_level, n_resamples=n_resamples)
    return ranking_table(band, sob)


def plot_ranking(table: pd.DataFrame, path_stem) -> dict:
    """Bar chart of a ``ranking_table``: per target, band width (left axis) beside S1 and ST with
    their confidence intervals (right axis).  Saved with ``figures.save_figure`` (PNG, PDF, CSV)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from spreadmap.design import BY_NAME
    from spreadmap.figures import save_figure

    targets = list(dict.fromkeys(table["target"]))
    fig, axes = plt.subplots(1, len(targets), figsize=(5.5 * len(targets), 4.2), squeeze=False)
    for ax, t in zip(axes[0], targets):
        sub = table[table["target"] == t].set_index("parameter").reindex(
            [p for p in NAMES if p in set(table["parameter"])])
        x = np.arange(len(sub))
        w = 0.27
        ax2 = ax.twinx()
        ax.bar(x - w, sub["band_width"], w, color="0.6", label="band width (left axis)")
        for off, col, colour in ((0.0, "S1", "tab:blue"), (w, "ST", "tab:red")):
            err = np.vstack([sub[col] - sub[f"{col}_ci_low"], sub[f"{col}_ci_high"] - sub[col]])
            err = np.where(np.isfinite(err), np.clip(err, 0, None), 0.0)
            ax2.bar(x + off, sub[col], w, yerr=err, capsize=3, color=colour,
                    label=f"{col} (right axis)")
        ax.set_xticks(x, [f"{BY_NAME[p].symbol}\nband #{int(rb)}\nST #{int(r)}" for p, rb, r in
                          zip(sub.index, sub["rank_band"], sub["rank_ST"])])
        ax.set_ylabel(f"band width of {t.upper()} [-]")
        ax2.set_ylabel("Sobol' index [-]")
        ax2.set_ylim(min(0.0, float(np.nanmin(sub[["S1", "ST"]].values)) - 0.02),
                     max(1.0, float(np.nanmax(sub["ST_ci_high"].fillna(sub["ST"]))) + 0.02))
        ax.set_title(f"Influence on {t.upper()} (#: rank by band width / by ST)")
        h1, l1 = ax.get_legend_handles_labels()
        h2, l2 = ax2.get_legend_handles_labels()
        ax.legend(h1 + h2, l1 + l2, loc="upper right", fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path_stem, table)
