"""Figures of the fidelity study: error against cost per preset (the Pareto figure) and the
one-knob-at-a-time sweeps. Each figure is written as PNG and PDF with its numbers as CSV."""
from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.ticker import NullFormatter

from ..design import TARGETS
from ..figures import new_figure, save_figure

TARGET_STYLE = {"mfr": ("MFR", "o", "tab:blue"), "pd": ("PD", "s", "tab:orange")}
KNOB_LABELS = {"width_d": "bed width [d]", "heap_height_d": "heap height [d]",
               "pile_length_min_d": "pile length [d] (particle count)", "heap_reserve": "heap reserve [-]",
               "transient_d": "transient [d]", "window_d": "measurement window [d]",
               "dt_factor": "time step / Rayleigh step [-]", "density_scale": "density scale [-] (1 = physical)"}


def pareto_front(cost: np.ndarray, error: np.ndarray) -> np.ndarray:
    """Indices of the presets no other preset beats on both cost and error, cheapest first."""
    order = np.argsort(cost, kind="stable")
    front, best = [], np.inf
    for i in order:
        if error[i] < best:
            front.append(i)
            best = error[i]
    return np.asarray(front, dtype=int)


def pareto_figure(presets: pd.DataFrame, reference: str, path_stem) -> dict:
    """Mean relative error of MFR and PD against the reference (over the points) versus the median
    CPU time per case; bars are the resolution of that error (2 standard errors of the seed means).

    Dashes mark each preset's noise floor; hollow markers are errors within the noise.

    Parameters
    ----------
    presets : pandas.DataFrame
        The per-preset table of ``spreadmap.fidelity.study.preset_errors`` (also the CSV saved).
    reference : str
        The reference preset (a row of `presets`; drawn at error 0).
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    fig = new_figure(7.5, 4.8)
    ax = fig.add_subplot()
    others = presets[presets["preset"] != reference].reset_index(drop=True)
    ref = presets[presets["preset"] == reference].iloc[0]
    cost = others["cpu_s_median"].to_numpy(dtype=float)
    offsets = {"mfr": 0.96, "pd": 1.04}  # side by side at the same cost
    for t in TARGETS:
        label, marker, colour = TARGET_STYLE[t]
        err = 100 * others[f"{t}_mean_abs_rel_error"].to_numpy(dtype=float)
        res = 100 * others[f"{t}_mean_rel_resolution"].to_numpy(dtype=float)
        resolved = others[f"{t}_chi2_p"].to_numpy(dtype=float) < 0.05
        ax.errorbar(cost * offsets[t], err, yerr=res, fmt="none", ecolor=colour, capsize=3)
        ax.plot(cost[resolved] * offsets[t], err[resolved], marker, color=colour, ms=7, ls="none",
                label=f"{label}: mean |error| over the points (filled: resolved, hollow: within noise)")
        ax.plot(cost[~resolved] * offsets[t], err[~resolved], marker, mfc="white", mec=colour, ms=7, ls="none")
        front = pareto_front(cost, err)
        ax.plot(cost[front] * offsets[t], err[front], "-", color=colour, lw=1, alpha=0.6)
        floor = 100 * others[f"{t}_noise_floor"].to_numpy(dtype=float)
        ax.plot(cost * offsets[t], floor, "_", color=colour, ms=14, mew=2, alpha=0.7, ls="none",
                label=f"{label}: noise floor (the mean |error| of a preset without any error, these seeds)")
    ax.axhline(5, color="k", ls="--", lw=0.8)
    ax.text(cost.min() * 0.8 if len(cost) else 1, 5, " goal 5 %", va="bottom", fontsize=8)
    for _, row in others.iterrows():
        flagged = f"\n{row['flagged_cases']} case(s) flagged" if row.get("flagged_cases", 0) else ""
        ax.annotate(f"{row['preset']}\n{row['cost_ratio_to_reference']:.0f}x cheaper{flagged}",
                    (row["cpu_s_median"], 100 * max(row["mfr_mean_abs_rel_error"], row["pd_mean_abs_rel_error"])),
                    textcoords="offset points", xytext=(8, 6), fontsize=8)
    ax.plot([ref["cpu_s_median"]], [0], "*", color="k", ms=12, clip_on=False, zorder=5,
            label=f"{reference} (error 0 by definition)")
    ax.annotate(reference, (ref["cpu_s_median"], 0), textcoords="offset points", xytext=(0, 10), ha="center",
                fontsize=8)
    ax.set_xscale("log")
    ax.set_xlabel("cost: median CPU time per case [s] (one core)")
    ax.set_ylabel(f"error against '{reference}' [%]")
    ax.set_ylim(bottom=0)
    ax.set_title("Speed against accuracy: each preset's error of MFR and PD and its cost\n"
                 "(bars: resolution, 2 standard errors of the seed means)", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    ax.grid(True, which="both", alpha=0.3)
    return save_figure(fig, path_stem, presets)


def knobs_figure(knobs: pd.DataFrame, base_preset: str, path_stem) -> dict:
    """One panel per knob: MFR and PD (seed mean, bar = seed SD) against the knob value, the base
    preset's value marked, the cost relative to it written above each value.

    Parameters
    ----------
    knobs : pandas.DataFrame
        The table of ``spreadmap.fidelity.study.knob_errors`` (also the CSV saved).
    base_preset : str
        The preset the knobs were varied from, named in the title.
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    names = list(dict.fromkeys(knobs["knob"]))
    ncols = min(3, len(names))
    nrows = int(np.ceil(len(names) / ncols))
    fig = new_figure(4.2 * ncols, 3.4 * nrows)
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False)).ravel()
    for ax, knob in zip(axes, names):
        rows = knobs[knobs["knob"] == knob].sort_values("value")
        x = rows["value"].to_numpy(dtype=float)
        for t in TARGETS:
            label, marker, colour = TARGET_STYLE[t]
            ax.errorbar(x, rows[f"{t}_mean"], yerr=rows[f"{t}_sd"], fmt=marker + "-", color=colour,
                        capsize=3, label=label)
        base = rows[rows["is_base"]]
        if len(base):
            ax.axvline(float(base["value"].iloc[0]), color="0.5", ls=":", lw=1)
        if knob == "density_scale" or (x.min() > 0 and x.max() / x.min() > 20):
            ax.set_xscale("log")
        ax.set_xticks(x, [f"{xi:g}\n{ratio:.2g}x" for xi, ratio in zip(x, rows["cost_ratio_to_base"])], fontsize=8)
        ax.minorticks_off()
        ax.set_xlabel(KNOB_LABELS.get(knob, knob) + "\n(value, CPU cost relative to the base)", fontsize=9)
        ax.set_ylabel("MFR, PD [-]")
        ax.grid(True, alpha=0.3)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    axes[0].legend(fontsize=8, loc="lower left")
    fig.suptitle(f"One knob at a time from '{base_preset}' (dotted: its value; bars: seed SD)", fontsize=10)
    return save_figure(fig, path_stem, knobs)


def correction_figure(result: dict, pairs: pd.DataFrame, path_stem, floor: str | None = None) -> dict:
    """Per target (spreadlab.paired_factor): each pair's and each point's reference / preset
    against h/d, the factor the maps take and its 95 % interval at a point not run.

    Parameters
    ----------
    result : dict
        The result of ``spreadlab.paired_factor.correction``.
    pairs : pandas.DataFrame
        The pairs it was computed from (``spreadlab.paired_factor.pairs``; also the CSV
        saved).
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.
    floor : str or None, optional
        The floor the cases ran on (spreadmap.case.substrate.floor_label), named on the figure
        and in the CSV.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    targets = list(result["targets"])
    fig = new_figure(5.2 * len(targets), 4.2)
    axes = fig.subplots(1, len(targets), squeeze=False)[0]
    for ax, t in zip(axes, targets):
        r = result["targets"][t]
        pts = pd.DataFrame(r["per_point"])
        ax.plot(pairs["h_over_d"], np.exp(pairs[f"{t}_l"]), "o", ms=3, color="0.6", label="a pair (one seed)")
        ax.errorbar(pts["h_over_d"], np.exp(pts["l"]), yerr=1.96 * pts["se"] * np.exp(pts["l"]), fmt="s", ms=5,
                    color="tab:blue", capsize=3, label="a point: mean of its pairs, 95 % (stated noise)")
        lo, hi = r["new_point_95"]
        ax.axhspan(lo, hi, color="tab:orange", alpha=0.18, label=f"at a point not run, 95 %: {lo:.3f}-{hi:.3f}")
        ax.axhline(r["factor"], color="tab:orange", lw=1.5, label=f"factor the maps take: {r['factor']:.3f}")
        ax.axhline(1.0, color="black", lw=0.8)
        ax.set_xscale("log")
        ticks = [x for x in (1, 1.2, 1.5, 2, 3, 5, 7) if 0.9 * pairs["h_over_d"].min() <= x <= 1.1 * pairs["h_over_d"].max()]
        ax.set_xticks(ticks, [f"{x:g}" for x in ticks])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("gap / particle diameter h/d [-]")
        ax.set_ylabel(f"{t.upper()}: {result['reference']} / {result['preset']} [-]")
        re = r["random_effects"]
        ax.set_title(f"{t.upper()}: {result['pairs']} pairs at {result['points']} points; points differ beyond noise: "
                     f"Q {re['q']:.1f} on {re['dof']} dof, p {re['q_p']:.2f}", fontsize=8)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
    return save_figure(fig, path_stem, pairs, floor)
