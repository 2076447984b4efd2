"""Powder maps at fixed machine settings (h, v).

* ``powder_band_map`` (a): each target against d, one curve per friction value, the lowest and the
  highest friction with their 95 % bands of the mean (model SD); stretches beyond the data dotted
  and hatched. Below each, the change from the lowest to the highest friction with its 95 %
  interval from joint draws: where that interval holds 0, the order of the friction curves (and
  so any crossing of them) is not resolved by the data.
* ``powder_cluster_map`` (b): in the MFR-y plane, one cluster of points per diameter, its points
  the friction values, each with a cross of one model SD; open marks beyond the data.

Each map's numbers come from ``powder_band_grid`` / ``powder_cluster_grid`` (no figure) and its
figure from ``draw_powder_band_map`` / ``draw_powder_cluster_map`` (the figure and those numbers as
its CSV); ``powder_band_map`` and ``powder_cluster_map`` do both.
"""
from __future__ import annotations

import matplotlib
import numpy as np
import pandas as pd
from matplotlib import colors as mcolors
from matplotlib.lines import Line2D

from .. import slices
from ..design import BY_NAME
from ..figures import new_figure, save_figure
from ..targets import axis_label, short
from . import grids
from .labels import end_label, right_labels
from .style import HATCH, MapResult, fmt, set_limits, support_note, with_model_note

POWDER = grids.MAP_DEFAULTS["powder"]
POWDER_SLICE = slices.POWDER  # f x d at fixed machine settings: the one definition, spreadmap.slices
BAND_SIZES = POWDER_SLICE.sizes  # map (a)'s grid, the one the loop's criteria read
DEFAULT_SUPPORT = grids.MAP_DEFAULTS["support"]
EFFECT = ("change", "change_low", "change_high", "p_increase")  # grids.f_effect's columns per target


def powder_band_map(model, stem, y: str = "pd", h_um: float = POWDER["h_um"], v_mm_s: float = POWDER["v_mm_s"],
                    n_d: int = BAND_SIZES["d_um"], n_f: int = BAND_SIZES["f"], d_values=None, f_values=None,
                    ranges=None, support=None, draws: int = 200, seed: int = 0, floor: str | None = None,
                    model_note: str | None = None) -> MapResult:
    """Powder map (a): MFR and y against d, one curve per friction value, at fixed machine settings (h, v).

    The lowest and the highest friction are drawn with their 95 % bands of the mean (model SD),
    stretches beyond the data dotted and hatched; below each panel, the change from the lowest to
    the highest friction with its 95 % interval from joint draws (see the module docstring). The
    numbers come from ``powder_band_grid``, the figure from ``draw_powder_band_map``.

    Parameters
    ----------
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate (``load_model``); it must model ``mfr`` and ``y``.
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv``.
    y : str, optional
        The second target drawn beside MFR.
    h_um : float, optional
        Layer thickness (gap) h [um]; default: the schema's ``maps.powder.h_um``.
    v_mm_s : float, optional
        Blade speed v [mm/s]; default: the schema's ``maps.powder.v_mm_s``.
    n_d, n_f : int, optional
        Grid sizes of the diameter d and the friction f, each spanning its range (ends included; at
        least 2).
    d_values : array_like or None, optional
        Explicit d values [um] instead of ``n_d`` (sorted); None: ``n_d`` over the range.
    f_values : array_like or None, optional
        Explicit f values [-] instead of ``n_f`` (sorted); None: ``n_f`` over the range.
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.
    support : dict or None, optional
        The config's ``maps.support`` (``max_distance``, ``max_sd_ratio``); None: the schema's.
    draws : int, optional
        Joint draws of the mean function for the friction effect's interval (``grids.f_effect``).
    seed : int, optional
        Seed of those draws.
    floor : str or None, optional
        The floor the cases ran on (``spreadmap.case.substrate.floor_label``), named on the figure
        and in the CSV.
    model_note : str or None, optional
        A line under the title naming the model drawn and its validation
        (``validation_note.validation_note``); None: none.

    Returns
    -------
    MapResult
        ``paths`` (``png``, ``pdf``, ``csv``), ``data``: ``powder_band_grid``'s table (f varying
        slowest; per row the change of MFR and y from the lowest to the highest f at its d:
        ``<t>_change``, ``_change_low``, ``_change_high``, ``_p_increase``), and ``info``: ``note``
        (the support note) and ``effect`` (the change per d).

    Raises
    ------
    ValueError
        If explicit d or f values are empty, or a grid size is below 2 (``grids.values``).
    """
    support = support or DEFAULT_SUPPORT
    table = powder_band_grid(model, y, h_um, v_mm_s, n_d, n_f, d_values, f_values, ranges, support, draws, seed)
    return draw_powder_band_map(table, stem, y, support, floor, model_note)


def powder_band_grid(model, y: str = "pd", h_um: float = POWDER["h_um"], v_mm_s: float = POWDER["v_mm_s"],
                     n_d: int = BAND_SIZES["d_um"], n_f: int = BAND_SIZES["f"], d_values=None, f_values=None,
                     ranges=None, support=None, draws: int = 200, seed: int = 0) -> pd.DataFrame:
    """The numbers of map (a): the (f, d) grid at (h, v), f varying slowest, evaluated for MFR and y
    (grids.evaluate), each row with the change of both from the lowest to the highest f at its d
    and that change's 95 % interval from joint draws (grids.f_effect)."""
    support = support or DEFAULT_SUPPORT
    axes, fixed = powder_slice(n_d, n_f, d_values, f_values, ranges, h_um, v_mm_s)
    targets = ["mfr", y]
    grid = grids.evaluate(model, POWDER_SLICE.frame(axes, fixed, ranges), targets, support)
    fv = axes["f"]
    effect = grids.f_effect(model, targets, fixed, axes["d_um"], fv[0], fv[-1], draws=draws, seed=seed)
    return grid.merge(effect, on="d_um", how="left")


def powder_slice(n_d, n_f, d_values, f_values, ranges, h_um, v_mm_s) -> tuple[dict, dict]:
    """The powder maps' slice (``spreadmap.slices.POWDER``): its f and d values and its fixed axes
    (h, v as given, any other axis at its nominal value)."""
    axes = POWDER_SLICE.axes(ranges=ranges, sizes={"d_um": n_d, "f": n_f}, given={"d_um": d_values, "f": f_values})
    return axes, POWDER_SLICE.fixed({"h_um": h_um, "v_mm_s": v_mm_s}, ranges)


def draw_powder_band_map(table: pd.DataFrame, stem, y: str, support: dict, floor: str | None = None,
                         model_note: str | None = None) -> MapResult:
    """Map (a) from ``powder_band_grid``'s table (or its CSV read back); saved with that table
    (``model_note``: a line under the title, as ``powder_band_map`` takes it)."""
    targets = ["mfr", y]
    fv, d = np.unique(table["f"]), np.unique(table["d_um"])
    effect = table[table["f"] == fv[0]][["d_um"] + [f"{t}_{c}" for t in targets for c in EFFECT]].reset_index(drop=True)
    shape = (len(fv), len(d))
    ok = table["supported"].to_numpy().reshape(shape)
    cmap = matplotlib.colormaps["plasma"]
    fcol = [cmap(0.8 * k / max(len(fv) - 1, 1)) for k in range(len(fv))]
    fig = new_figure(12.5, 8.2)
    axes = fig.subplots(2, 2, height_ratios=[2.2, 1], sharex=True)
    for col, t in enumerate(targets):
        ax = axes[0, col]
        z = table[t].to_numpy().reshape(shape)
        s = table[f"{t}_model_sd"].to_numpy().reshape(shape)
        for k in (0, len(fv) - 1):
            ax.fill_between(d, z[k] - 1.96 * s[k], z[k] + 1.96 * s[k], color=fcol[k], alpha=0.18, lw=0)
        for k in range(len(fv)):
            edge = k in (0, len(fv) - 1)
            lw = 2.2 if edge else 1.0
            ax.plot(d, np.where(ok[k], z[k], np.nan), color=fcol[k], lw=lw)
            ax.plot(d, z[k], color=fcol[k], lw=lw * 0.7, ls=":")
        beyond = ~ok.any(axis=0)
        if beyond.any():
            lo, hi = ax.get_ylim()
            ax.fill_between(d, lo, hi, where=beyond, step="mid", zorder=0, **HATCH)
            ax.set_ylim(lo, hi)
        ax.set_ylabel(axis_label(t))
        ax.set_xlim(d.min(), d.max() + 0.2 * np.ptp(d))
        right_labels(ax, d[-1], z[:, -1], [BY_NAME["f"].text(x) for x in fv], fcol)
        ax.set_title(f"{short(t)} against particle diameter; shaded: 95 % band of the mean "
                     f"(f = {fmt(fv[0])}, {fmt(fv[-1])})", fontsize=9)
        ax.grid(alpha=0.3)
        ax2 = axes[1, col]
        ch = effect[f"{t}_change"].to_numpy()
        ax2.fill_between(d, effect[f"{t}_change_low"], effect[f"{t}_change_high"], color="0.6", alpha=0.35, lw=0,
                         label="95 % interval (joint draws)")
        ax2.plot(d, ch, color="k", lw=1.5, label=f"{short(t)}(f = {fmt(fv[-1])}) - {short(t)}(f = {fmt(fv[0])})")
        ax2.axhline(0, color="darkred", lw=0.8)
        resolved = (effect[f"{t}_change_low"] > 0) | (effect[f"{t}_change_high"] < 0)
        ax2.set_title(f"effect of friction: resolved (interval excludes 0) at {int(resolved.sum())} of {len(d)} diameters",
                      fontsize=9)
        ax2.set_xlabel(BY_NAME["d_um"].label)
        ax2.set_ylabel(f"change of {short(t)} [-]")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=7, loc="best")
    handles = [Line2D([], [], color="0.3", lw=2, label="supported by the data"),
               Line2D([], [], color="0.3", lw=1.4, ls=":", label="beyond the data")]
    axes[0, 0].legend(handles=handles, fontsize=7.5, loc="best")
    fig.suptitle(f"Powder map (a): friction f = {fmt(fv[0])}-{fmt(fv[-1])} as the diameter varies, "
                 f"at {slices.text(POWDER_SLICE.fixed_of(table))}" + with_model_note(model_note), fontsize=11)
    note = support_note(fig, table["supported"].to_numpy(), support)
    paths = save_figure(fig, stem, table, floor)
    return MapResult(paths, table, {"note": note, "effect": effect})


def powder_cluster_map(model, stem, y: str = "pd", h_um: float = POWDER["h_um"], v_mm_s: float = POWDER["v_mm_s"], n_d: int = 5,
                       n_f: int = 7, d_values=None, f_values=None, ranges=None, support=None,
                       floor: str | None = None) -> MapResult:
    """Powder map (b): in the MFR-y plane, one cluster of points per diameter, its points the friction values.

    Each point has a cross of one model SD; points beyond the data are open. The numbers come from
    ``powder_cluster_grid``, the figure from ``draw_powder_cluster_map``.

    Parameters
    ----------
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate (``load_model``); it must model ``mfr`` and ``y``.
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv``.
    y : str, optional
        The target on the y axis.
    h_um : float, optional
        Layer thickness (gap) h [um]; default: the schema's ``maps.powder.h_um``.
    v_mm_s : float, optional
        Blade speed v [mm/s]; default: the schema's ``maps.powder.v_mm_s``.
    n_d, n_f : int, optional
        Grid sizes of the diameter d (the clusters) and the friction f (the points of a cluster),
        each spanning its range (ends included; at least 2).
    d_values : array_like or None, optional
        Explicit d values [um] instead of ``n_d`` (sorted); None: ``n_d`` over the range.
    f_values : array_like or None, optional
        Explicit f values [-] instead of ``n_f`` (sorted); None: ``n_f`` over the range.
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.
    support : dict or None, optional
        The config's ``maps.support`` (``max_distance``, ``max_sd_ratio``); None: the schema's.
    floor : str or None, optional
        The floor the cases ran on (``spreadmap.case.substrate.floor_label``), named on the figure
        and in the CSV.

    Returns
    -------
    MapResult
        ``paths`` (``png``, ``pdf``, ``csv``), ``data``: the evaluated (f, d) grid at (h, v), f
        varying slowest (``grids.evaluate``), and ``info``: ``note`` (the support note).

    Raises
    ------
    ValueError
        If explicit d or f values are empty, or a grid size is below 2 (``grids.values``).
    """
    support = support or DEFAULT_SUPPORT
    grid = powder_cluster_grid(model, y, h_um, v_mm_s, n_d, n_f, d_values, f_values, ranges, support)
    return draw_powder_cluster_map(grid, stem, y, support, floor)


def powder_cluster_grid(model, y: str = "pd", h_um: float = POWDER["h_um"], v_mm_s: float = POWDER["v_mm_s"],
                        n_d: int = 5, n_f: int = 7, d_values=None, f_values=None, ranges=None, support=None) -> pd.DataFrame:
    """The numbers of map (b): the (f, d) grid at (h, v), f varying slowest, evaluated for MFR and y."""
    support = support or DEFAULT_SUPPORT
    axes, fixed = powder_slice(n_d, n_f, d_values, f_values, ranges, h_um, v_mm_s)
    return grids.evaluate(model, POWDER_SLICE.frame(axes, fixed, ranges), ["mfr", y], support)


def draw_powder_cluster_map(grid: pd.DataFrame, stem, y: str, support: dict, floor: str | None = None) -> MapResult:
    """Map (b) from ``powder_cluster_grid``'s grid (or its CSV read back); saved with that grid."""
    fv, d = np.unique(grid["f"]), np.unique(grid["d_um"])
    shape = (len(fv), len(d))
    X, Y = grid["mfr"].to_numpy().reshape(shape), grid[y].to_numpy().reshape(shape)
    sx, sy = grid["mfr_model_sd"].to_numpy().reshape(shape), grid[f"{y}_model_sd"].to_numpy().reshape(shape)
    ok = grid["supported"].to_numpy().reshape(shape)
    cmap = mcolors.LinearSegmentedColormap.from_list("vd", matplotlib.colormaps["viridis"](np.linspace(0, 0.9, 256)))
    dnorm = mcolors.Normalize(d.min(), d.max())
    sizes = 15 + 85 * (fv - fv.min()) / (np.ptp(fv) or 1.0)
    fig = new_figure(8.6, 6.4)
    ax = fig.subplots()
    set_limits(ax, np.concatenate([(X - sx).ravel(), (X + sx).ravel()]),
               np.concatenate([(Y - sy).ravel(), (Y + sy).ravel()]), pad=0.1, pad_right=0.22, pad_top=0.12)
    cb = fig.colorbar(matplotlib.cm.ScalarMappable(norm=dnorm, cmap=cmap), ax=ax, pad=0.02)
    cb.set_label(BY_NAME["d_um"].label)
    placed = []
    for j in range(len(d)):
        c = cmap(dnorm(d[j]))
        ax.errorbar(X[:, j], Y[:, j], xerr=sx[:, j], yerr=sy[:, j], fmt="none", ecolor=c, alpha=0.45, lw=0.8, zorder=2)
        ax.plot(X[:, j], Y[:, j], color=c, lw=1.0, alpha=0.8, zorder=2)
        ax.scatter(X[ok[:, j], j], Y[ok[:, j], j], s=sizes[ok[:, j]], color=c, edgecolor="black", lw=0.4, zorder=3)
        ax.scatter(X[~ok[:, j], j], Y[~ok[:, j], j], s=sizes[~ok[:, j]], facecolor="white", edgecolor=c, lw=1.2,
                   zorder=3)
        end_label(ax, X[:, j], Y[:, j], BY_NAME["d_um"].text(d[j]), at="start", fontsize=9, distance=10,
                  edge=mcolors.to_hex(c), placed=placed)
    handles = [Line2D([], [], marker="o", ls="-", color="0.5", mec="black", ms=5,
                      label=f"{len(fv)} friction values {fmt(fv[0])}-{fmt(fv[-1])}, marker size grows with f"),
               Line2D([], [], marker="+", ls="", color="0.4", ms=9, label="± one model SD"),
               Line2D([], [], marker="o", ls="", mfc="white", mec="0.3", ms=6, label="beyond the data")]
    ax.legend(handles=handles, loc="best", fontsize=7.5, framealpha=0.9)
    ax.set_xlabel(axis_label("mfr"))
    ax.set_ylabel(axis_label(y))
    ax.set_title(f"Powder map (b): clusters of constant diameter as friction varies, at "
                 f"{slices.text(POWDER_SLICE.fixed_of(grid))}", fontsize=10)
    ax.grid(alpha=0.3)
    note = support_note(fig, grid["supported"].to_numpy(), support)
    paths = save_figure(fig, stem, grid, floor)
    return MapResult(paths, grid, {"note": note})
