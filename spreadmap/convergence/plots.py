"""Figures of the convergence analysis and of the sampling study.

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

from ..figures import new_figure, save_figure
from ..table import usable
from . import study_rule as cv

TARGET_LABELS = {"mfr": "MFR [-]", "pd": "PD [-]"}
STAT_LABELS = {
    "mean": "mean [-]",
    "std": "standard deviation (ddof=1) [-]",
    "median": "median [-]",
    "kurtosis": "excess kurtosis (Fisher) [-]",
    "skewness": "skewness [-]",
}
N_LABEL = "number of cases N [-]"


def _label(target: str) -> str:
    return TARGET_LABELS.get(target, f"{target} [-]")


# ----------------------------------------------------------------------------------------------
# (1) distributions per partition
# ----------------------------------------------------------------------------------------------
def partition_values(table: pd.DataFrame, sweep: str, targets: Sequence[str] = cv.DEFAULT_TARGETS,
                     partitions: Iterable[int] | None = None, order_col: str = "index",
                     partition_col: str | None = None) -> pd.DataFrame:
    """Long frame (sweep, partition, target, value) of the usable target values per partition.

    Partitions as in ``convergence.convergence_table``: prefixes of ``order_col`` order
    (``partitions`` = their sizes) or, with ``partition_col``, one group per value (lattices),
    labelled by the group size.
    """
    parts: list[tuple[int, pd.DataFrame]] = []
    if partition_col is not None:
        for _, g in table.groupby(partition_col, sort=False):
            parts.append((len(g), g.loc[usable(g)]))
        parts.sort(key=lambda p: p[0])
    else:
        ordered = table.sort_values(order_col, kind="stable")
        keep = usable(ordered)
        if partitions is None:
            partitions = sorted({int(n) for n in np.unique(np.geomspace(
                min(16, len(ordered)), len(ordered), 5).astype(int))})
        parts = [(int(n), ordered.iloc[:int(n)][keep[:int(n)]]) for n in partitions]
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
    the sweep ended (the floor rule of ``convergence`` applies to skewness and kurtosis).
    With a partition sweep among them, the axes start at its smallest partition: a case-by-case
    curve's first few cases swing over a range that would flatten the rest (the CSV keeps them).
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


# ----------------------------------------------------------------------------------------------
# (3) the sampling study
# ----------------------------------------------------------------------------------------------
def plot_sampling_study(table: pd.DataFrame, path_stem,
                        summary: pd.DataFrame | None = None) -> dict[str, Path]:
    """Cases needed per design, per function: each seed as a dot, median with IQR bars.

    ``table``: ``sampling_study.run_study`` output; ``summary`` defaults to
    ``sampling_study.summarise(table)``.  Runs that did not converge within the budget are drawn
    at the budget as open upward triangles (censored).  The CSV holds the tidy table joined with
    the summary columns (median, q25, q75, iqr, not_converged) of its group.
    """
    from .sampling_study import summarise  # local: keeps the plot module import-light

    summ = summarise(table) if summary is None else summary
    keys = ["function", "method", "schedule"]
    present = set(summ[["method", "schedule"]].itertuples(index=False, name=None))
    order = [("lattice", "lattice_sizes"), ("lds", "lattice_sizes"), ("random", "lattice_sizes"),
             ("lds", "case"), ("random", "case")]
    groups = [g for g in order if g in present] + sorted(present - set(order))
    method_color = {"lds": "C0", "random": "C1", "lattice": "C2"}
    functions = list(dict.fromkeys(summ["function"]))
    fig = new_figure(max(6.0, 2.4 * len(functions)), 4.8)
    ax = fig.subplots()
    width = 0.8 / max(len(groups), 1)
    for gi, (method, sched) in enumerate(groups):
        c = method_color.get(method, f"C{3 + gi}")
        filled = sched == "lattice_sizes"
        label = f"{method}, checked at {'k^4 cases' if filled else 'every case'}"
        for fi, fn in enumerate(functions):
            x = fi - 0.4 + width * (gi + 0.5)
            sel = table[(table["function"] == fn) & (table["method"] == method)
                        & (table["schedule"] == sched)]
            if sel.empty:
                continue
            v = sel["n_converged"].to_numpy(dtype=float)
            budget = sel["budget"].to_numpy(dtype=float)
            jitter = np.linspace(-0.3, 0.3, v.size) * width if v.size > 1 else np.zeros(1)
            ok = np.isfinite(v)
            ax.scatter(x + jitter[ok], v[ok], s=10, color=c, alpha=0.5)
            ax.scatter(x + jitter[~ok], budget[~ok], s=24, marker="^", facecolors="none",
                       edgecolors=c)
            row = summ[(summ["function"] == fn) & (summ["method"] == method)
                       & (summ["schedule"] == sched)].iloc[0]
            kw = dict(color=c, mfc=c if filled else "white", mec=c, ms=7, capsize=3)
            if np.isfinite(row["median"]):
                lo = row["median"] - row["q25"]
                hi = (row["q75"] - row["median"]) if np.isfinite(row["q75"]) else 0.0
                ax.errorbar([x], [row["median"]], yerr=[[lo], [hi]], fmt="s" if filled else "o",
                            label=label if fi == 0 else None, **kw)
            elif fi == 0:
                ax.plot([], [], "s" if filled else "o", label=label, color=c,
                        mfc=kw["mfc"], mec=c)
    for b in np.unique(table["budget"].to_numpy(dtype=float)):
        ax.axhline(b, color="0.5", ls="--", lw=0.8)
    ax.set_yscale("log")
    ax.set_xticks(range(len(functions)), functions)
    ax.set_xlabel("test function")
    ax.set_ylabel("cases needed to converge N [-]")
    ax.set_title("cases until the criterion holds for good: seeds (dots), median and IQR; "
                 "^ = not converged within the budget (dashed)", fontsize="small")
    ax.legend(fontsize="x-small", ncol=2)
    data = table.merge(summ[keys + ["median", "q25", "q75", "iqr", "not_converged"]], on=keys,
                       how="left")
    return save_figure(fig, path_stem, data)


# ----------------------------------------------------------------------------------------------
# (4) the sampling study with noise
# ----------------------------------------------------------------------------------------------
NOISE_TITLES = {"mult3": "3 % multiplicative noise", "mult7": "7 % multiplicative noise",
                "counting": "counting noise 0.45/sqrt(N), per-case SD known"}
METHOD_STYLE = {"lds": ("C0", "o"), "random": ("C1", "v"), "lattice": ("C2", "s"), "active": ("C3", "D"),
                "active_per_cpu": ("C4", "^")}


def plot_noisy_study(table: pd.DataFrame, summary: pd.DataFrame, path_stem) -> dict[str, Path]:
    """Map RMSE against the number of cases, one panel per noise model: median over seeds
    (line and markers) and the band between the quartiles, each method in its colour; the
    targets of ``summary`` as dotted lines.  CSV: the median and quartiles behind the lines."""
    from .noisy_study import rmse_summary  # local: keeps the plot module import-light

    rs = rmse_summary(table)
    noises = list(dict.fromkeys(table["noise"]))
    fig = new_figure(4.2 * len(noises), 4.2)
    axes = np.atleast_1d(fig.subplots(1, len(noises), sharey=True))
    for ax, z in zip(axes, noises):
        for m in dict.fromkeys(table["method"]):
            g = rs[(rs["noise"] == z) & (rs["method"] == m)].sort_values("n")
            if g.empty:
                continue
            c, mk = METHOD_STYLE.get(m, ("C4", "x"))
            ax.fill_between(g["n"], g["q25"], g["q75"], color=c, alpha=0.18, lw=0)
            ax.plot(g["n"], g["median"], color=c, marker=mk, ms=4, lw=1.4,
                    label=f"{m} ({int(g['runs'].max())} seeds)")
        for t in sorted(set(summary["target"])):
            ax.axhline(t, color="0.3", ls=":", lw=1)
            ax.annotate(f"target {t:g}", (1.0, t), xycoords=("axes fraction", "data"),
                        ha="right", va="bottom", fontsize="x-small", color="0.3")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(NOISE_TITLES.get(z, z), fontsize="small")
        ax.set_xlabel(N_LABEL)
        ax.xaxis.set_minor_formatter(NullFormatter())
        ticks = [16, 32, 64, 128, 256, 512]
        ax.set_xticks([t for t in ticks if t <= table["n"].max() * 1.05],
                      [str(t) for t in ticks if t <= table["n"].max() * 1.05])
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel("map RMSE against the truth (MFR units) [-]")
    axes[0].legend(fontsize="x-small")
    fig.suptitle("GP map error by sampling design: median over seeds, band = quartiles", fontsize="small")
    return save_figure(fig, path_stem, rs)


def plot_cost_study(table: pd.DataFrame, targets: Sequence[float], path_stem) -> dict[str, Path]:
    """Map RMSE against cases (left) and against the CPU hours they cost (right), per design:
    median over seeds at each checkpoint (the CPU too), band = quartiles of the RMSE; the targets
    as dotted lines.  CSV: the medians and quartiles behind the lines."""
    g = table.groupby(["method", "n"])
    rs = pd.DataFrame({"median": g["map_rmse"].median(), "q25": g["map_rmse"].quantile(0.25),
                       "q75": g["map_rmse"].quantile(0.75), "cpu_h": g["cpu_cases"].median() / 3600,
                       "runs": g.size()}).reset_index()
    fig = new_figure(9.0, 4.2)
    axes = fig.subplots(1, 2, sharey=True)
    for m in dict.fromkeys(table["method"]):
        s = rs[rs["method"] == m].sort_values("n")
        c, mk = METHOD_STYLE.get(m, ("C5", "x"))
        for ax, x in zip(axes, (s["n"], s["cpu_h"])):
            ax.fill_between(x, s["q25"], s["q75"], color=c, alpha=0.18, lw=0)
            ax.plot(x, s["median"], color=c, marker=mk, ms=4, lw=1.4, label=f"{m} ({int(s['runs'].max())} seeds)")
    for ax in axes:
        for t in targets:
            ax.axhline(t, color="0.3", ls=":", lw=1)
        ax.set_yscale("log")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_xlabel(N_LABEL)
    axes[1].set_xlabel("CPU hours of the cases (the scene's cost law) [h]")
    axes[0].set_ylabel("map RMSE against the truth (MFR units) [-]")
    axes[1].legend(fontsize="x-small")
    fig.suptitle("Map error per case and per CPU hour (counting noise): median over seeds, band = quartiles",
                 fontsize="small")
    return save_figure(fig, path_stem, rs)


# ----------------------------------------------------------------------------------------------
# (5) the path of `snakemake converge`
# ----------------------------------------------------------------------------------------------
CRITERION_LABELS = {"map_error": "map error / tolerance (the larger of CV net of noise, posterior)",
                    "cv_rmse": "CV RMSE / (factor x noise SD)",
                    "map_change": "map change / (fraction x noise SD)",
                    "ci": "CI half-width / tolerance (worst statistic)"}


def plot_converge_path(record: Mapping, path_stem) -> dict[str, Path]:
    """Each map criterion's value (ratio to its threshold: <= 1 holds) at every batch, the
    study's rule (its largest change / its tolerance) beside them, and why the run stopped."""
    path = record["criteria"]["path"]
    rows = []
    for h in path:
        for c in CRITERION_LABELS:
            if h.get(c):
                rows.append({"n": h["n"], "criterion": c, "ratio": h[c]["value"], "holds": h[c]["holds"]})
    tol = float(record.get("study_rule_tolerance", cv.DEFAULT_TOLERANCE))
    for h in record.get("study_rule_path", []):
        if h.get("max_change") is not None and np.isfinite(h["max_change"]):
            rows.append({"n": h["n"], "criterion": "study_rule", "ratio": h["max_change"] / tol,
                         "holds": h["max_change"] < tol})
    data = pd.DataFrame(rows, columns=["n", "criterion", "ratio", "holds"])
    fig = new_figure(7.0, 4.4)
    ax = fig.subplots()
    labels = {**CRITERION_LABELS, "study_rule": f"study's rule: largest change / {tol:g} (reported)"}
    for i, (c, lab) in enumerate(labels.items()):
        g = data[data["criterion"] == c]
        if g.empty:
            continue
        req = c in record["criteria"]["stop_on"]
        ax.plot(g["n"], g["ratio"], marker="o", ms=4, color=f"C{i}", ls="-" if req else "--",
                label=lab + ("" if req or c == "study_rule" else " (not required)"))
    ax.axhline(1.0, color="k", lw=1)
    ax.set_yscale("log")
    ax.set_xlabel(N_LABEL)
    ax.set_ylabel("criterion / its threshold [-] (<= 1 holds)")
    ax.set_title(f"converge: {record['reason']} after {record['n']} cases", fontsize="small")
    ax.legend(fontsize="x-small")
    ax.grid(True, alpha=0.3)
    return save_figure(fig, path_stem, data)
