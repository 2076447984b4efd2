"""Figures of the surrogate's validation (PNG + PDF, the numbers behind each as CSV).

* ``plot_parity``: out-of-fold predictions of the map model against the DEM values, one panel per
  target, with 95 % prediction-interval bars and the validation numbers (RMSE and its interval
  against the noise SD, coverage, R^2 against its ceiling) of both models.
* ``plot_study``: the study's protocol (held-out R^2 against neurons, min-max over the seeds)
  beside the cross-validated R^2 of the noise-aware models and the ceiling R^2_max.
* ``plot_learning_curve``: cross-validated RMSE against the number of LDS cases, with the noise SD.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import norm

from ..figures import new_figure, save_figure
from . import validation

COLOURS = {"gp": "tab:blue", "mlp": "tab:orange"}
LONG = {"mfr": "MFR", "pd": "PD", "layer_packing": "layer packing", "coverage": "coverage",
        "roughness_d": "roughness / d", "thickness_ratio": "layer thickness / h"}


def _numbers(v: pd.Series) -> str:
    return (f"{v['model'].upper()}: RMSE {v['rmse']:.3f} [{v['rmse_low']:.3f}, {v['rmse_high']:.3f}]"
            f" vs noise {v['noise_sd']:.3f} ({v['noise_source']})\n"
            f"   {v['level']:.0%} PI coverage {v['coverage']:.2f} [{v['coverage_low']:.2f}, {v['coverage_high']:.2f}]; "
            f"R$^2$ {v['r2']:.2f} of max {v['r2_max']:.2f} (noise-corrected {v['r2_corrected']:.2f})")


def plot_parity(val: pd.DataFrame, oof: pd.DataFrame, stem) -> dict:
    targets = list(dict.fromkeys(val["target"]))
    fig = new_figure(5.6 * len(targets), 6.0)
    axes = np.atleast_1d(fig.subplots(1, len(targets)))
    tables = []
    for ax, t in zip(axes, targets):
        v = val[val["target"] == t]
        chosen = v[v["map_model"]].iloc[0]
        case = validation.per_case(oof[(oof["target"] == t) & (oof["model"] == chosen["model"])])
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
        ax.set_xlabel(f"DEM {LONG.get(t, t)} [-]")
        ax.set_ylabel(f"surrogate {LONG.get(t, t)} [-] (case left out)")
        ax.set_title(f"{LONG.get(t, t)}: {int(chosen['n_cases'])} cases, {int(chosen['repeats'])}x k-fold", fontsize=10)
        text = "\n".join(_numbers(r) + ("  (maps)" if r["map_model"] else "") for _, r in v.iterrows())
        ax.text(0.02, 0.98, text, transform=ax.transAxes, va="top", fontsize=6.8,
                bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))
        ax.legend(loc="lower right", fontsize=7)
        ax.grid(alpha=0.3)
        tables.append(case.assign(target=t, model=chosen["model"]))
    return save_figure(fig, stem, pd.concat(tables, ignore_index=True))


def plot_study(summary: pd.DataFrame, val: pd.DataFrame, stem) -> dict:
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
        ax.set_title(LONG.get(t, t), fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6.5, loc="lower left")
    return save_figure(fig, stem, summary)


def plot_learning_curve(learning: pd.DataFrame, stem) -> dict:
    fig = new_figure(6.4, 4.6)
    ax = fig.subplots()
    if learning.empty:
        ax.text(0.5, 0.5, "no learning curve (too few LDS cases)", ha="center", transform=ax.transAxes)
    for i, t in enumerate(dict.fromkeys(learning["target"])):
        lc = learning[learning["target"] == t].sort_values("n_cases")
        c = f"C{i}"
        yerr = np.vstack([lc["rmse"] - lc["rmse_low"], lc["rmse_high"] - lc["rmse"]])
        ax.errorbar(lc["n_cases"], lc["rmse"], yerr=yerr, fmt="o-", capsize=4, color=c,
                    label=f"{LONG.get(t, t)} ({lc['model'].iloc[0].upper()}): cross-validated RMSE, 95 % interval")
        ax.plot(lc["n_cases"], lc["noise_sd"], ls=":", color=c, label=f"{LONG.get(t, t)}: noise SD of one run")
    ax.set_xlabel("LDS cases used (prefix of the sequence)")
    ax.set_ylabel("RMSE against the DEM values [-]")
    ax.set_title("learning curve: cross-validated error against the noise of one run", fontsize=10)
    ax.grid(alpha=0.3)
    if not learning.empty:
        ax.legend(fontsize=7)
    return save_figure(fig, stem, learning)


def plot_all(result, outdir, prefix: str = "surrogate") -> dict:
    """The three figures and the tables (validation metrics, study, out-of-fold) into outdir."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    result.validation.to_csv(outdir / f"{prefix}_metrics.csv", index=False)
    result.study_runs.to_csv(outdir / f"{prefix}_study_runs.csv", index=False)
    return {
        "parity": plot_parity(result.validation, result.oof, outdir / f"{prefix}_parity"),
        "r2_vs_neurons": plot_study(result.study_summary, result.validation, outdir / f"{prefix}_r2_vs_neurons"),
        "learning_curve": plot_learning_curve(result.learning, outdir / f"{prefix}_learning_curve"),
    }
