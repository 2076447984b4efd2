"""Figures of the study's rule: the distributions per partition and the statistics against N.

Every figure is written as PNG and PDF with the numbers behind it as CSV beside it
(``save_figure``).  Figures are built on ``matplotlib.figure.Figure`` objects rendered by the Agg
canvas: no pyplot, no global state, safe in parallel workflow jobs.  Functions take DataFrames and
an output path stem (``results/convergence/statistics`` -> ``statistics.png``, ``.pdf``,
``.csv``) and return the paths written.
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.ticker import NullFormatter

from .. import targets as registry
from ..figures import N_LABEL, new_figure, save_figure
from ..table import partition, usable_cases
from . import rule as cv

STAT_LABELS = {
    "mean": "mean [-]",
    "std": "standard deviation (ddof=1) [-]",
    "median": "median [-]",
    "kurtosis": "excess kurtosis (Fisher) [-]",
    "skewness": "skewness [-]",
}


def _label(target: str) -> str:
    return f"{registry.short(target)} [{registry.REGISTRY[target].unit}]" if target in registry.REGISTRY else f"{target} [-]"


# ----------------------------------------------------------------------------------------------
# (1) distributions per partition
# ----------------------------------------------------------------------------------------------
def partition_values(table: pd.DataFrame, sweep: str, targets: Sequence[str] = cv.DEFAULT_TARGETS,
                     partitions: Iterable[int] | None = None, order_col: str = "index",
                     partition_col: str | None = None) -> pd.DataFrame:
    """Long frame (sweep, partition, target, value) of the usable target values per partition.

    Partitions as in ``rule.convergence_table``: prefixes of ``order_col`` order
    (``partitions`` = their sizes) or, with ``partition_col``, one group per value (lattices),
    labelled by the group size.

    Parameters
    ----------
    table : pandas.DataFrame
        The results table's rows of one sweep.
    sweep : str
        The sweep's name, written in the ``sweep`` column.
    targets : sequence of str, optional
        The targets (columns) whose values are listed.
    partitions : iterable of int or None, optional
        Prefix mode: the partition sizes; None: five sizes spaced geometrically from
        min(16, rows) to all rows.
    order_col : str, optional
        Prefix mode: the column giving the cases' order in the sequence.
    partition_col : str or None, optional
        Group mode: the column whose values name the partitions (lattices).

    Returns
    -------
    pandas.DataFrame
        Columns ``sweep``, ``partition`` (N), ``target`` and ``value``: one row per usable case,
        finite value, partition and target.
    """
    parts: list[tuple[int, pd.DataFrame]] = []
    if partition_col is not None:
        for _, g in table.groupby(partition_col, sort=False):
            parts.append((len(g), usable_cases(g)))
        parts.sort(key=lambda p: p[0])
    else:
        if partitions is None:
            partitions = sorted({int(n) for n in np.unique(np.geomspace(
                min(16, len(table)), len(table), 5).astype(int))})
        parts = [(int(n), usable_cases(partition(table, n, sweep=None, order_col=order_col))) for n in partitions]
    frames = []
    for n, g in parts:
        for t in targets:
            v = g[t].to_numpy(dtype=float)
            v = v[np.isfinite(v)]
            frames.append(pd.DataFrame({"sweep": sweep, "partition": n, "target": t, "value": v}))
    return pd.concat(frames, ignore_index=True)


def plot_distributions(long_df: pd.DataFrame, path_stem,
                       targets: Sequence[str] = cv.DEFAULT_TARGETS, floor: str | None = None) -> dict[str, Path]:
    """Box plots of each target per partition, one column per sweep (e.g. LDS | lattice).

    ``long_df``: columns sweep, partition, target, value (``partition_values`` of each sweep,
    concatenated).  Boxes: quartiles, whiskers 1.5 IQR, the mean as a triangle.  Rows share
    the y axis so the sweeps compare directly.

    Parameters
    ----------
    long_df : pandas.DataFrame
        Columns sweep, partition, target, value (also the CSV saved).
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.
    targets : sequence of str, optional
        The targets, one row of panels each.
    floor : str or None, optional
        The floor the cases ran on (spreadmap.case.substrate.floor_label), named on the figure
        and in the CSV.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    sweeps = list(dict.fromkeys(long_df["sweep"]))
    fig = new_figure(4.2 * len(sweeps), 3.0 * len(targets))
    axes = fig.subplots(len(targets), len(sweeps), squeeze=False, sharey="row")
    for i, t in enumerate(targets):
        for j, s in enumerate(sweeps):
            ax = axes[i, j]
            sub = long_df[(long_df["sweep"] == s) & (long_df["target"] == t)]
            ns = sorted(sub["partition"].unique())
            data = [sub.loc[sub["partition"] == n, "value"].to_numpy() for n in ns]
            if data:
                ax.boxplot(data, tick_labels=[str(n) for n in ns], showmeans=True)
            ax.set_title(f"{s}: {t.upper()} per partition")
            ax.set_xlabel(N_LABEL)
            ax.set_ylabel(_label(t))
            ax.tick_params(axis="x", labelrotation=45)
    return save_figure(fig, path_stem, long_df, floor)


# ----------------------------------------------------------------------------------------------
# (2) statistics against N
# ----------------------------------------------------------------------------------------------
def _stats_long(name: str, df: pd.DataFrame, targets, tolerance, floors) -> pd.DataFrame:
    fl = cv._floors(floors)
    n = df["partition"].to_numpy() if "partition" in df.columns else df.index.to_numpy()
    frames = []
    for t in targets:
        for s in cv.STATISTICS:
            col = f"{t}_{s}"
            if col not in df.columns:
                continue
            v = df[col].to_numpy(dtype=float)
            final = v[np.isfinite(v)][-1] if np.isfinite(v).any() else np.nan
            half = tolerance * max(abs(final), fl[s]) if np.isfinite(final) else np.nan
            frames.append(pd.DataFrame({"sweep": name, "n": n, "target": t, "statistic": s,
                                        "value": v, "final": final, "band_low": final - half,
                                        "band_high": final + half}))
    return pd.concat(frames, ignore_index=True)


def plot_statistics(sweeps: Mapping[str, pd.DataFrame], path_stem,
                    targets: Sequence[str] = cv.DEFAULT_TARGETS,
                    tolerance: float = cv.DEFAULT_TOLERANCE,
                    floors: Mapping[str, float] | None = None, floor: str | None = None) -> dict[str, Path]:
    """Each statistic against N (log x) for every sweep, with the tolerance band of each sweep.

    ``sweeps``: name -> statistics frame, either a ``convergence_table`` (column ``partition``)
    or a ``running_statistics`` frame (index ``n``).  The band is final value
    +- tolerance * max(|final|, floor): the set of values within the criterion's reach of where
    the sweep ended (the floor rule of ``rule`` applies to skewness and kurtosis).
    With a partition sweep among them, the axes start at its smallest partition: a case-by-case
    curve's first few cases swing over a range that would flatten the rest (the CSV keeps them).

    Parameters
    ----------
    sweeps : Mapping of str to pandas.DataFrame
        Sweep name -> statistics frame (see above).
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv`` (the statistics in long form
        with their bands).
    targets : sequence of str, optional
        The targets, one column of panels each.
    tolerance : float, optional
        The criterion's tolerance (0.005 = 0.5 %), the bands' half-width relative to the final
        value.
    floors : Mapping of str to float or None, optional
        Denominator floors per statistic (``rule.DEFAULT_FLOORS`` for the ones left out).
    floor : str or None, optional
        The floor the cases ran on (spreadmap.case.substrate.floor_label), named on the figure
        and in the CSV.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    long_df = pd.concat([_stats_long(k, v, targets, tolerance, floors) for k, v in sweeps.items()],
                        ignore_index=True)
    fig = new_figure(4.5 * len(targets), 2.4 * len(cv.STATISTICS))
    axes = fig.subplots(len(cv.STATISTICS), len(targets), squeeze=False, sharex=True)
    colors = {name: f"C{i}" for i, name in enumerate(sweeps)}
    n_from = _scaled_from(sweeps)
    for j, t in enumerate(targets):
        for i, s in enumerate(cv.STATISTICS):
            ax = axes[i, j]
            for name in sweeps:
                sub = long_df[(long_df["sweep"] == name) & (long_df["target"] == t)
                              & (long_df["statistic"] == s)]
                if sub.empty:
                    continue
                c = colors[name]
                marker = "o" if len(sub) <= 60 else None
                ax.plot(sub["n"], sub["value"], color=c, marker=marker, ms=3, lw=1, label=name)
                ax.axhspan(sub["band_low"].iloc[0], sub["band_high"].iloc[0], color=c, alpha=0.15,
                           label=f"{name} final +- {tolerance:.2%} band")
            panel = long_df[(long_df["target"] == t) & (long_df["statistic"] == s)]
            limits = statistic_limits(panel, n_from)
            if limits is not None:
                ax.set_ylim(*limits)
            ax.set_xscale("log")
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_ylabel(f"{t.upper()} {STAT_LABELS[s]}")
            if i == len(cv.STATISTICS) - 1:
                ax.set_xlabel(N_LABEL)
            if i == 0:
                ax.set_title(f"{t.upper()} statistics against N")
    if n_from > 1:  # a case-by-case curve's first few cases are left off (they are in the CSV)
        axes[0, 0].set_xlim(n_from / 1.15, long_df["n"].max() * 1.15)
        ticks = _partition_sizes(sweeps)
        axes[0, 0].set_xticks(ticks, [str(n) for n in ticks])  # shared x: every panel's ticks
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncol=min(len(labels), 3), fontsize="small")
    return save_figure(fig, path_stem, long_df, floor)


def _partition_sizes(sweeps: Mapping[str, pd.DataFrame]) -> list[int]:
    """Every partition size (N) of the partition sweeps among ``sweeps``, sorted."""
    return sorted({int(n) for v in sweeps.values() if "partition" in v.columns for n in v["partition"]})


def _scaled_from(sweeps: Mapping[str, pd.DataFrame]) -> int:
    """The N from which the y axes are scaled: the smallest partition of any partition sweep (a
    case-by-case curve's first few cases swing over a range that would flatten everything else)."""
    sizes = _partition_sizes(sweeps)
    return sizes[0] if sizes else 1


def statistic_limits(panel: pd.DataFrame, n_from: int, pad: float = 0.08) -> tuple[float, float] | None:
    """y limits of one statistic's panel: every value at N >= n_from and every sweep's band, padded
    by ``pad`` of their span (None when nothing finite is left)."""
    values = np.concatenate([panel.loc[panel["n"] >= n_from, "value"].to_numpy(dtype=float),
                             panel["band_low"].to_numpy(dtype=float), panel["band_high"].to_numpy(dtype=float)])
    values = values[np.isfinite(values)]
    if not values.size:
        return None
    low, high = values.min(), values.max()
    span = high - low if high > low else max(abs(high), 1e-12)
    return low - pad * span, high + pad * span

