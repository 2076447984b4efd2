"""Figures of the DEM-free experiments: the sampling study (``sampling_study``), the sampling study
with noise (``noisy_study``) and the map per CPU hour (``cost_study``).

Written as PNG, PDF and the CSV behind them by ``figures.save_figure``; functions take the
studies' tables and an output path stem and return the paths written.  They draw what the study
modules compute and import nothing that draws.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd
from matplotlib.ticker import NullFormatter

from spreadmap.figures import N_LABEL, new_figure, save_figure


# ----------------------------------------------------------------------------------------------
# (1) the sampling study
# ----------------------------------------------------------------------------------------------
def plot_sampling_study(table: pd.DataFrame, path_stem,
                        summary: pd.DataFrame | None = None) -> dict[str, Path]:
    """Cases needed per design, per function: each seed as a dot, median with IQR bars.

    Runs that did not converge within the budget are drawn at the budget as open upward triangles
    (censored). The CSV holds the tidy table joined with the summary columns (median, q25, q75, iqr,
    not_converged) of its group.

    Parameters
    ----------
    table : pandas.DataFrame
        ``sampling_study.run_study`` output.
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.
    summary : pandas.DataFrame or None, optional
        ``sampling_study.summarise(table)``; None: computed here.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    from spreadlab.experiments.sampling_study import summarise  # local: keeps the plot module import-light

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
# (2) the sampling study with noise
# ----------------------------------------------------------------------------------------------
NOISE_TITLES = {"mult3": "3 % multiplicative noise", "mult7": "7 % multiplicative noise",
                "counting": "counting noise 0.45/sqrt(N), per-case SD known"}
METHOD_STYLE = {"lds": ("C0", "o"), "random": ("C1", "v"), "lattice": ("C2", "s"), "active": ("C3", "D"),
                "active_per_cpu": ("C4", "^")}


def plot_noisy_study(table: pd.DataFrame, summary: pd.DataFrame, rs: pd.DataFrame, path_stem) -> dict[str, Path]:
    """Map RMSE against the number of cases, one panel per noise model.

    Median over seeds (line and markers) and the band between the quartiles, each method in its
    colour; the targets of ``summary`` as dotted lines. CSV: the median and quartiles behind the
    lines.

    Parameters
    ----------
    table : pandas.DataFrame
        ``noisy_study.run``'s table.
    summary : pandas.DataFrame
        ``noisy_study.summarise``'s table (its ``target`` values are drawn).
    rs : pandas.DataFrame
        ``noisy_study.rmse_summary(table)`` (also the CSV saved).
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
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
    """Map RMSE against cases (left) and against the CPU hours they cost (right), per design.

    Median over seeds at each checkpoint (the CPU too), band = quartiles of the RMSE; the targets as
    dotted lines. CSV: the medians and quartiles behind the lines.

    Parameters
    ----------
    table : pandas.DataFrame
        ``noisy_study.run``'s table (``method``, ``n``, ``map_rmse``, ``cpu_cases`` [s]).
    targets : sequence of float
        The map-RMSE targets drawn (MFR units).
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``); the CSV per
        (method, n): ``median``, ``q25``, ``q75`` of the RMSE, ``cpu_h`` [h] (median) and ``runs``.
    """
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

