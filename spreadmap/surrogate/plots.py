"""Figures of the surrogate's validation (PNG + PDF, the numbers behind each as CSV).

* ``plot_parity``: out-of-fold predictions of the map model (``validation.parity_table``) against
  the DEM values, one panel per target, with 95 % prediction-interval bars and the validation
  numbers (RMSE and its interval against the noise SD, coverage, R^2 against its ceiling) of both
  models.
* ``plot_study``: the study's protocol (held-out R^2 against neurons, min-max over the seeds)
  beside the cross-validated R^2 of the noise-aware models and the ceiling R^2_max.
* ``plot_learning_curve``: cross-validated RMSE against the number of LDS cases, with the noise SD.
* ``plot_heldout``: held-out checks (tools/heldout.py score): each point's seed mean against
  the prediction made before its runs, with the interval it was scored against, one panel per
  target, one marker per check; and every point's z with its RMS per target and check.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import norm

from ..figures import new_figure, save_figure
from ..targets import phrase
from . import validation

COLOURS = {"gp": "tab:blue", "mlp": "tab:orange"}


def _numbers(v: pd.Series) -> str:
    return (f"{v['model'].upper()}: RMSE {v['rmse']:.3f} [{v['rmse_low']:.3f}, {v['rmse_high']:.3f}]"
            f" vs noise {v['noise_sd']:.3f} ({v['noise_source']})\n"
            f"   {v['level']:.0%} PI coverage {v['coverage']:.2f} [{v['coverage_low']:.2f}, {v['coverage_high']:.2f}]; "
            f"R$^2$ {v['r2']:.2f} of max {v['r2_max']:.2f} (noise-corrected {v['r2_corrected']:.2f})")


def plot_parity(val: pd.DataFrame, parity: pd.DataFrame, stem, floor: str | None = None) -> dict:
    """``val``: the validation metrics (surrogate_metrics.csv); ``parity``: ``validation.parity_table``
    (or this figure's CSV read back), drawn and saved as the figure's CSV."""
    targets = list(dict.fromkeys(val["target"]))
    fig = new_figure(5.6 * len(targets), 6.0)
    axes = np.atleast_1d(fig.subplots(1, len(targets)))
    for ax, t in zip(axes, targets):
        v = val[val["target"] == t]
        chosen = v[v["map_model"]].iloc[0]
        case = parity[parity["target"] == t]
        z = norm.ppf(0.5 + chosen["level"] / 2)
        ax.errorbar(case["y"], case["mean"], yerr=z * case["run_sd"], fmt="o", ms=4, color=COLOURS[chosen["model"]],
                    ecolor="0.7", elinewidth=0.8, label=f"out-of-fold prediction ({chosen['model'].upper()}), "
                                                         f"bars: {chosen['level']:.0%} interval of a new run")
        if case["case_sd"].notna().all():
            ax.errorbar(case["y"], case["mean"], xerr=case["case_sd"], fmt="none", ecolor="0.45", elinewidth=0.6,
                        label="DEM value ± its noise SD")
        lo = float(min(case["y"].min(), case["mean"].min()))
        hi = float(max(case["y"].max(), case["mean"].max()))
        pad = 0.08 * (hi - lo if hi > lo else 1.0)
        x = np.array([lo - pad, hi + pad])
        ax.plot(x, x, "k--", lw=1, label="y = x")
        ax.set_xlim(x)
        ax.set_ylim(x)
        ax.set_aspect("equal")
        ax.set_xlabel(f"DEM {phrase(t)} [-]")
        ax.set_ylabel(f"surrogate {phrase(t)} [-] (case left out)")
        ax.set_title(f"{phrase(t)}: {int(chosen['n_cases'])} cases, {int(chosen['repeats'])}x k-fold", fontsize=10)
        text = "\n".join(_numbers(r) + ("  (maps)" if r["map_model"] else "") for _, r in v.iterrows())
        ax.text(0.02, 0.98, text, transform=ax.transAxes, va="top", fontsize=6.8,
                bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))
        ax.legend(loc="lower right", fontsize=7)
        ax.grid(alpha=0.3)
    return save_figure(fig, stem, parity, floor)


def plot_study(summary: pd.DataFrame, val: pd.DataFrame, stem, floor: str | None = None) -> dict:
    targets = list(dict.fromkeys(summary["target"]))
    fig = new_figure(5.0 * len(targets), 4.6)
    axes = np.atleast_1d(fig.subplots(1, len(targets)))
    for ax, t in zip(axes, targets):
        s = summary[summary["target"] == t].sort_values("neurons")
        yerr = np.vstack([s["r2_mean"] - s["r2_min"], s["r2_max"] - s["r2_mean"]])
        ax.errorbar(s["neurons"], s["r2_mean"], yerr=yerr, fmt="o-", capsize=4, color="0.3",
                    label=f"study's protocol: held-out R$^2$ ({int(s['n_test'].iloc[0])} cases), "
                          f"mean and min-max over {int(s['n_seeds'].iloc[0])} seeds")
        ch = s[s["chosen"]]
        ax.plot(ch["neurons"], ch["r2_mean"], "*", ms=14, color="gold", mec="k",
                label="size the study picks (on its own test cases)")
        for _, v in val[val["target"] == t].iterrows():
            ax.axhline(v["r2"], color=COLOURS[v["model"]], lw=1.6,
                       label=f"{v['model'].upper()}, cross-validated R$^2$ {v['r2']:.2f}")
        r2max = float(val.loc[val["target"] == t, "r2_max"].iloc[0])
        ax.axhline(r2max, color="k", ls=":", label=f"ceiling R$^2_{{max}}$ = {r2max:.2f} (noise)")
        ax.set_xscale("log", base=2)
        ax.set_xticks(s["neurons"], [str(int(n)) for n in s["neurons"]])
        ax.set_xlabel("hidden neurons (one hidden layer)")
        ax.set_ylabel("R$^2$")
        lo = min(float(s["r2_min"].min()), float(val["r2"].min()))
        ax.set_ylim(max(lo - 0.05, -0.5), 1.02)
        ax.set_title(phrase(t), fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6.5, loc="lower left")
    return save_figure(fig, stem, summary, floor)


def plot_learning_curve(learning: pd.DataFrame, stem, floor: str | None = None) -> dict:
    fig = new_figure(6.4, 4.6)
    ax = fig.subplots()
    if learning.empty:
        ax.text(0.5, 0.5, "no learning curve (too few LDS cases)", ha="center", transform=ax.transAxes)
    for i, t in enumerate(dict.fromkeys(learning["target"])):
        lc = learning[learning["target"] == t].sort_values("n_cases")
        c = f"C{i}"
        yerr = np.vstack([lc["rmse"] - lc["rmse_low"], lc["rmse_high"] - lc["rmse"]])
        ax.errorbar(lc["n_cases"], lc["rmse"], yerr=yerr, fmt="o-", capsize=4, color=c,
                    label=f"{phrase(t)} ({lc['model'].iloc[0].upper()}): cross-validated RMSE, 95 % interval")
        ax.plot(lc["n_cases"], lc["noise_sd"], ls=":", color=c, label=f"{phrase(t)}: noise SD of one run")
    ax.set_xlabel("LDS cases used (prefix of the sequence)")
    ax.set_ylabel("RMSE against the DEM values [-]")
    ax.set_title("learning curve: cross-validated error against the noise of one run", fontsize=10)
    ax.grid(alpha=0.3)
    if not learning.empty:
        ax.legend(fontsize=7)
    return save_figure(fig, stem, learning, floor)


def plot_all(result, outdir, prefix: str = "surrogate", floor: str | None = None) -> dict:
    """The three figures of the surrogate's validation into outdir (the tables they draw from: the caller writes them).

    The parity figure (``plot_parity``, from ``validation.parity_table``), the study's protocol
    (``plot_study``) and the learning curve (``plot_learning_curve``); with ``floor``
    (spreadmap.case.substrate.floor_label) the figures name the floor the cases ran on.

    Parameters
    ----------
    result : spreadmap.surrogate.fitting.SurrogateResult
        ``fit_surrogate``'s result: its ``validation``, ``oof``, ``study_summary`` and
        ``learning`` tables are drawn.
    outdir : pathlib.Path or str
        The folder of the figures (created if missing).
    prefix : str, optional
        The files' name prefix: ``<prefix>_parity``, ``<prefix>_r2_vs_neurons``,
        ``<prefix>_learning_curve`` (each .png, .pdf and .csv).
    floor : str or None, optional
        The floor the cases ran on, named on each figure and in its CSV; None: not named.

    Returns
    -------
    dict
        ``parity``, ``r2_vs_neurons`` and ``learning_curve`` -> the files written for that figure
        (``png``, ``pdf``, ``csv`` -> pathlib.Path).
    """
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    return {
        "parity": plot_parity(result.validation, validation.parity_table(result.validation, result.oof),
                              outdir / f"{prefix}_parity", floor),
        "r2_vs_neurons": plot_study(result.study_summary, result.validation, outdir / f"{prefix}_r2_vs_neurons", floor),
        "learning_curve": plot_learning_curve(result.learning, outdir / f"{prefix}_learning_curve", floor),
    }


def plot_heldout(scores: dict[str, pd.DataFrame], stem, level: float = 0.95) -> dict:
    """Held-out checks: each point's seed mean against the prediction made before its runs, and every point's z.

    Each point is drawn at (prediction, seed mean) over a vertical bar, the `level` interval of its
    seed mean about the prediction (centred on the y = x line), so a point is inside when its marker
    lies on its bar; points outside are ringed in red. One panel per target, one marker per check;
    the last panel: every point's z per target and check, with its RMS.

    Parameters
    ----------
    scores : dict of str to pandas.DataFrame
        Check label -> its score table (tools/heldout.py score's CSV: name, target, predicted,
        seed_mean, n_runs, sd_of_mean, z, inside; scored at `level`).
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv`` (the score tables with their
        ``check``).
    level : float, optional
        The level of the intervals the points were scored at, in (0, 1).

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    frames = [t.assign(check=label) for label, t in scores.items()]
    table = pd.concat(frames, ignore_index=True)
    targets = list(dict.fromkeys(table["target"]))
    ncols = min(4, len(targets) + 1)  # the last panel: every point's z, target by target
    nrows = -(-(len(targets) + 1) // ncols)
    fig = new_figure(4.2 * ncols, 4.2 * nrows + 0.4)
    axes = np.atleast_1d(fig.subplots(nrows, ncols)).ravel()
    z = norm.ppf(0.5 + level / 2)
    markers = ["o", "s", "^", "D"]
    for ax, t in zip(axes, targets):
        rows = table[table["target"] == t]
        for i, (label, r) in enumerate(rows.groupby("check", sort=False)):
            inside = r["inside"].astype(bool)
            n_in = int(inside.sum())
            # the bar is the interval the point was scored against, centred on the prediction
            ax.errorbar(r["predicted"], r["predicted"], yerr=z * r["sd_of_mean"], fmt="none", ecolor=f"C{i}",
                        alpha=0.35, elinewidth=5)
            ax.plot(r.loc[inside, "predicted"], r.loc[inside, "seed_mean"], markers[i % 4], color=f"C{i}", ms=5,
                    label=f"{label}: {n_in} of {len(r)} inside")
            if n_in < len(r):
                ax.plot(r.loc[~inside, "predicted"], r.loc[~inside, "seed_mean"], markers[i % 4], mfc="none",
                        mec="tab:red", ms=7)
        lo = float(min(rows["predicted"].min(), rows["seed_mean"].min()))
        hi = float(max(rows["predicted"].max(), rows["seed_mean"].max()))
        pad = 0.1 * (hi - lo if hi > lo else 1.0)
        x = np.array([lo - pad, hi + pad])
        ax.plot(x, x, "k--", lw=0.8)
        ax.set_xlim(x)
        ax.set_ylim(x)
        ax.set_aspect("equal")
        ax.set_xlabel(f"predicted {phrase(t)} (before the runs) [-]")
        ax.set_ylabel(f"DEM {phrase(t)}, mean over seeds [-]")
        ax.set_title(phrase(t), fontsize=10)
        ax.legend(loc="upper left", fontsize=7)
        ax.grid(alpha=0.3)
    _heldout_z(axes[len(targets)], table, targets, z, markers)
    for ax in axes[len(targets) + 1:]:
        ax.set_visible(False)
    fig.suptitle(f"Held-out points: seed means against the predictions; bars: the {level:.0%} interval of each "
                 f"seed mean (the model's SD and the noise of its runs)", fontsize=9)
    return save_figure(fig, stem, table)


def _heldout_z(ax, table: pd.DataFrame, targets: list, z_level: float, markers: list) -> None:
    """Every point's z = (seed mean - prediction) / the SD it was scored with, per target: inside
    the band |z| <= z_level the point is inside its interval; z scattered much more narrowly than
    the band (mean z^2 well below 1) says the intervals are too wide."""
    checks = list(dict.fromkeys(table["check"]))
    width = 0.6 / max(len(checks), 1)
    for i, label in enumerate(checks):
        for j, t in enumerate(targets):
            r = table[(table["check"] == label) & (table["target"] == t)]
            if not len(r):
                continue
            x = j - 0.3 + width * (i + 0.5) + np.linspace(-0.3, 0.3, len(r)) * width
            ax.plot(x, r["z"], markers[i % 4], color=f"C{i}", ms=4, alpha=0.8,
                    label=label.split(" (")[0] if j == 0 else None)
            ax.plot([j - 0.3 + width * i, j - 0.3 + width * (i + 1)], [np.sqrt(np.mean(r["z"] ** 2))] * 2, "-",
                    color=f"C{i}", lw=2)
    ax.axhspan(-z_level, z_level, color="0.9", zorder=0)
    top = max(z_level + 0.6, float(np.nanmax(np.abs(table["z"]))) + 0.3)
    ax.set_ylim(-top, top)
    ax.axhline(1.0, color="0.5", lw=0.8, ls=":")
    ax.axhline(-1.0, color="0.5", lw=0.8, ls=":")
    ax.set_xticks(range(len(targets)), [phrase(t) for t in targets], rotation=35, ha="right", fontsize=8)
    ax.set_ylabel("z = (seed mean - prediction) / its SD [-]")
    ax.set_title(f"z of every point; grey: |z| <= {z_level:.2f}; bars: RMS z (1 if the intervals are right)",
                 fontsize=8)
    ax.legend(loc="lower left", fontsize=7)
    ax.grid(alpha=0.3, axis="y")
