"""Figures of the surrogate validation (matplotlib, Agg backend).

Every figure is written as ``<stem>.png`` and ``<stem>.pdf`` with the numbers behind it in
``<stem>.csv`` (and, for the parity plot, the fit lines in ``<stem>_fit.csv``).

* ``plot_parity``: DEM (x) against surrogate (y) on the held-out cases, one panel per target,
  with the y = x line and the least-squares line (slope, intercept and R^2 in the legend).
* ``plot_r2_vs_neurons``: held-out R^2 against the hidden-neuron count, mean over the seeds with
  min-max bars, per target; the GP baseline as a horizontal line.
* ``plot_learning_curve``: held-out R^2 against the number of LDS cases used.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from .design import TARGETS  # noqa: E402
from .figures import save_figure  # noqa: E402

LABELS = {"mfr": "MFR [-]", "pd": "PD [-]"}
NAMES_LONG = {"mfr": "mass flow rate MFR", "pd": "packing density PD"}
COLORS = {"mfr": "tab:blue", "pd": "tab:orange"}


def plot_parity(parity: pd.DataFrame, parity_fit: pd.DataFrame, stem: str | Path) -> list[Path]:
    """Parity plot: columns of ``parity``: target, case_id, dem, predicted, predicted_std;
    of ``parity_fit``: target, slope, intercept, r2."""
    targets = [t for t in TARGETS if t in set(parity["target"])]
    fig, axes = plt.subplots(1, len(targets), figsize=(5.2 * len(targets), 4.8), squeeze=False)
    for ax, t in zip(axes[0], targets):
        p = parity[parity["target"] == t]
        fit = parity_fit[parity_fit["target"] == t].iloc[0]
        ax.errorbar(p["dem"], p["predicted"], yerr=p["predicted_std"], fmt="o", ms=4, alpha=0.75,
                    color=COLORS.get(t), ecolor="0.6", elinewidth=0.8, label=f"held-out cases (n = {len(p)}; bars: ensemble std)")
        lo = float(min(p["dem"].min(), p["predicted"].min()))
        hi = float(max(p["dem"].max(), p["predicted"].max()))
        pad = 0.05 * (hi - lo if hi > lo else 1.0)
        x = np.array([lo - pad, hi + pad])
        ax.plot(x, x, "k--", lw=1, label="y = x")
        ax.plot(x, fit["slope"] * x + fit["intercept"], "r-", lw=1.2,
                label=f"fit: slope {fit['slope']:.4f}, intercept {fit['intercept']:+.4f}\n"
                      f"R$^2$ = {fit['r2']:.5f}")
        ax.set_xlim(x)
        ax.set_ylim(x)
        ax.set_aspect("equal")
        ax.set_xlabel(f"DEM {LABELS.get(t, t)}")
        ax.set_ylabel(f"surrogate {LABELS.get(t, t)}")
        ax.set_title(f"{NAMES_LONG.get(t, t)}" + (f" ({int(fit['neurons'])} neurons)" if "neurons" in fit else ""))
        ax.legend(loc="upper left", fontsize=8)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    paths = save_figure(fig, stem, parity)
    fit_csv = Path(stem).with_name(Path(stem).name + "_fit.csv")
    parity_fit.to_csv(fit_csv, index=False)
    return list(paths.values()) + [fit_csv]


def plot_r2_vs_neurons(metrics: pd.DataFrame, stem: str | Path) -> list[Path]:
    """R^2 against neuron count from ``surrogate.metrics_table`` (rows model == "mlp": mean with
    min-max bars; model == "gp": horizontal baseline)."""
    mlp = metrics[metrics["model"] == "mlp"]
    gp = metrics[metrics["model"] == "gp"]
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for t in TARGETS:
        m = mlp[mlp["target"] == t].sort_values("neurons")
        if m.empty:
            continue
        yerr = np.vstack([m["r2_mean"] - m["r2_min"], m["r2_max"] - m["r2_mean"]])
        ax.errorbar(m["neurons"], m["r2_mean"], yerr=yerr, fmt="o-", capsize=4, color=COLORS.get(t),
                    label=f"MLP {t.upper()} (mean, min-max over seeds)")
        ch = m[m["chosen"].astype(bool)]
        ax.plot(ch["neurons"], ch["r2_mean"], "*", ms=14, color=COLORS.get(t), mec="k",
                label=f"chosen for {t.upper()}")
        g = gp[gp["target"] == t]
        if len(g):
            ax.axhline(float(g["r2_mean"].iloc[0]), ls=":", color=COLORS.get(t),
                       label=f"GP baseline {t.upper()} (R$^2$ = {float(g['r2_mean'].iloc[0]):.5f})")
    ax.set_xscale("log", base=2)
    ns = sorted(mlp["neurons"].unique())
    ax.set_xticks(ns)
    ax.set_xticklabels([str(int(n)) for n in ns])
    ax.set_xlabel("hidden neurons (one hidden layer)")
    ax.set_ylabel("held-out R$^2$")
    ax.set_title("surrogate accuracy against network size")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return list(save_figure(fig, stem, metrics).values())


def plot_learning_curve(learning: pd.DataFrame, stem: str | Path) -> list[Path]:
    """Held-out R^2 against the number of LDS cases used (``surrogate.learning_curve``)."""
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for t in TARGETS:
        lc = learning[learning["target"] == t].sort_values("n_cases")
        if lc.empty:
            continue
        yerr = np.vstack([lc["r2_mean"] - lc["r2_min"], lc["r2_max"] - lc["r2_mean"]])
        ax.errorbar(lc["n_cases"], lc["r2_mean"], yerr=yerr, fmt="o-", capsize=4, color=COLORS.get(t),
                    label=f"MLP {t.upper()} (mean, min-max over seeds)")
        if "gp_r2" in lc and lc["gp_r2"].notna().any():
            ax.plot(lc["n_cases"], lc["gp_r2"], "s:", color=COLORS.get(t), mfc="none",
                    label=f"GP {t.upper()}")
    if learning.empty:
        ax.text(0.5, 0.5, "no learning curve (no LDS cases)", ha="center", transform=ax.transAxes)
    ax.set_xlabel("LDS cases used (prefix of the sequence)")
    ax.set_ylabel("held-out R$^2$ (fixed test cases)")
    ax.set_title("learning curve")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return list(save_figure(fig, stem, learning).values())


def plot_all(result, outdir: str | Path, prefix: str = "surrogate") -> dict:
    """All three figures and the metrics table of a ``surrogate.SurrogateResult`` into outdir."""
    from .surrogate import metrics_table

    outdir = Path(outdir)
    metrics = metrics_table(result, outdir / f"{prefix}_metrics.csv")
    return {
        "metrics": [outdir / f"{prefix}_metrics.csv"],
        "parity": plot_parity(result.parity, result.parity_fit, outdir / f"{prefix}_parity"),
        "r2_vs_neurons": plot_r2_vs_neurons(metrics, outdir / f"{prefix}_r2_vs_neurons"),
        "learning_curve": plot_learning_curve(result.learning, outdir / f"{prefix}_learning_curve"),
    }
