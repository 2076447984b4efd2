"""Regimes: where the DEM cases of each regime lie, and the surrogate's probability of each regime.

Left: the usable DEM cases in the (h/d, v) plane coloured by their DEM regime. Right: over the
(d, h) plane at a fixed friction and speed, the probability that a new DEM run falls in each
regime (``grids.regime_probabilities``: the thresholds of ``metrics.classify`` on the predictive
distribution of MFR and PD), drawn as the most probable regime's colour with contours of
P(jamming) and P(short feed) at 0.1, 0.5 and 0.9; beyond the data hatched; the line h = d (a gap of
one particle). Cases of a size distribution (``size_span`` > 0) are placed by h/D90 of their feed
instead of h/d (the coarse tail decides whether spheres pass the gap), and the right panel adds the
line h = D90 (D90 / D50 of the cases' feeds, their median: ``coarse_ratio``). ``counts``: DEM
regime against the most probable regime at the cases' own settings (the final model on its
training cases: a consistency check, not a validation).

``regime_tables`` computes the numbers (no figure), ``draw_regime_overlay`` draws them;
``regime_overlay`` does both and writes the plane's numbers beside the figure (``<stem>_plane.csv``;
the figure's own CSV holds the cases).
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib import colors as mcolors
from matplotlib.lines import Line2D

from .. import design, slices
from ..design import BY_NAME, h_over_d
from ..figures import new_figure, save_figure
from ..files import atomic_path
from . import grids
from .style import MapResult, support_note

PLANE = grids.MAP_DEFAULTS["regime_plane"]
PLANE_SLICE = slices.REGIME_PLANE  # d x h at fixed f, v: the one definition, spreadmap.slices
PLANE_SIZES = PLANE_SLICE.sizes

REGIMES = ("normal", "jamming", "short_feed")
COLOURS = {"normal": "tab:green", "jamming": "tab:red", "short_feed": "tab:orange"}
MARKERS = {"normal": "o", "jamming": "X", "short_feed": "s"}
NAMES_LONG = {"normal": "normal extrusion", "jamming": "jamming", "short_feed": "short feed"}
# the plane's numbers written beside the figure (after the point's NAMES): its support, the predictive normal of
# each target the rule reads (mean, SD of a new run) and the regime probabilities drawn from them
PLANE_COLUMNS = ["data_distance", "supported", *(c for t in grids.REGIME_TARGETS for c in (t, f"{t}_run_sd")),
                 "p_normal", "p_jamming", "p_short_feed"]


def most_probable(frame: pd.DataFrame) -> np.ndarray:
    P = frame[["p_normal", "p_jamming", "p_short_feed"]].to_numpy()
    return np.array(REGIMES, dtype=object)[np.argmax(P, axis=1)]


def coarse_ratio(cases: pd.DataFrame) -> float | None:
    """D90 / D50 of the cases' feeds (their median) where the cases hold a size distribution.

    Parameters
    ----------
    cases : pandas.DataFrame
        Cases with ``size_span``, ``feed_d50_um`` and ``feed_d90_um`` (``spreadmap.metrics.sizes``).

    Returns
    -------
    float or None
        The median ratio over the cases with ``size_span`` > 0 and both quantiles finite; None
        when there are none (spheres of one size, or a table from before the columns).
    """
    if not {"size_span", "feed_d50_um", "feed_d90_um"} <= set(cases.columns):
        return None
    span = pd.to_numeric(cases["size_span"], errors="coerce").to_numpy(float)
    ratio = (pd.to_numeric(cases["feed_d90_um"], errors="coerce")
             / pd.to_numeric(cases["feed_d50_um"], errors="coerce")).to_numpy(float)
    ok = (span > 0) & np.isfinite(ratio)
    return float(np.median(ratio[ok])) if ok.any() else None


def regime_counts(dem: np.ndarray, model: np.ndarray) -> pd.DataFrame:
    return pd.DataFrame({"dem": [int((dem == r).sum()) for r in REGIMES],
                         "surrogate": [int((model == r).sum()) for r in REGIMES],
                         "both": [int(((dem == r) & (model == r)).sum()) for r in REGIMES]},
                        index=pd.Index(REGIMES, name="regime"))


def regime_overlay(cases: pd.DataFrame, model, stem, rules: dict,
                   f: float = PLANE["f"], v_mm_s: float = PLANE["v_mm_s"], n_d: int = PLANE_SIZES["d_um"],
                   n_h: int = PLANE_SIZES["h_um"], ranges=None,
                   support=None, floor: str | None = None) -> MapResult:
    """The regime figure and the plane's numbers beside it.

    The figure (``stem``.png/.pdf, the cases' table as ``stem``.csv): left, the cases in the
    (h/d, v) plane by DEM regime; right, the most probable regime of a new run over the (d, h) plane
    at (f, v) with probability contours (see the module docstring). The plane's numbers are written
    beside it (``stem``_plane.csv: ``NAMES`` and ``PLANE_COLUMNS``, and ``floor`` when given). The numbers come
    from ``regime_tables``, the figure from ``draw_regime_overlay``.

    Parameters
    ----------
    cases : pandas.DataFrame
        The results table (physical units, NAMES; ``regime``, ``mfr``, ``pd``); cases whose regime
        is not one of ``REGIMES`` are left out and counted in the title.
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate; it must model ``mfr``, ``coverage`` and ``thickness_ratio``.
    stem : pathlib.Path or str
        Where to save the figure and its CSVs.
    rules : dict
        The config's ``regime`` section: ``jam_mfr_max``, ``short_feed_coverage_min``,
        ``short_feed_thickness_min`` (``metrics.classify``'s thresholds).
    f : float, optional
        Friction coefficient [-] of the plane; default: the schema's ``maps.regime_plane.f``.
    v_mm_s : float, optional
        Blade speed [mm/s] of the plane; default: the schema's ``maps.regime_plane.v_mm_s``.
    n_d, n_h : int, optional
        Grid sizes of d and h over their ranges (ends included; at least 2).
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.
    support : dict or None, optional
        The config's ``maps.support`` (``max_distance``, ``max_sd_ratio``); None: the schema's.
    floor : str or None, optional
        The floor the cases ran on (``spreadmap.case.substrate.floor_label``), named on the figure
        and in both CSVs.

    Returns
    -------
    MapResult
        ``paths`` (``png``, ``pdf``, ``csv`` and ``plane``), ``data``: the cases with a DEM regime
        (their h/d, regime probabilities at their own settings and most probable regime), and
        ``info``: ``counts`` (per regime: cases by the DEM, by the surrogate, by both), ``excluded``,
        ``agree``, ``plane`` (the plane's table) and ``note`` (the support note).

    Raises
    ------
    ValueError
        If the surrogate lacks a target the regime rule reads, or a grid size is below 2.
    """
    support = support or grids.MAP_DEFAULTS["support"]
    table, plane = regime_tables(cases, model, rules, f, v_mm_s, n_d, n_h, ranges, support)
    excluded = len(cases) - len(table)
    res = draw_regime_overlay(table, plane, stem, excluded, support, floor)
    res.paths["plane"] = res.paths["csv"].with_name(f"{res.paths['csv'].stem}_plane.csv")
    with atomic_path(res.paths["plane"]) as tmp:
        plane[[*design.NAMES, *PLANE_COLUMNS]].assign(**({"floor": floor} if floor else {})).to_csv(tmp, index=False)
    return res


def regime_tables(cases: pd.DataFrame, model, rules: dict, f: float = PLANE["f"], v_mm_s: float = PLANE["v_mm_s"],
                  n_d: int = PLANE_SIZES["d_um"], n_h: int = PLANE_SIZES["h_um"], ranges=None,
                  support=None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The numbers of the regime overlay: (the cases with a DEM regime, each with its h/d, the
    regime probabilities at its own settings and the most probable regime; the (d, h) plane at
    (f, v), d varying slowest, evaluated for the rule's targets with each regime's probability)."""
    support = support or grids.MAP_DEFAULTS["support"]
    known = cases["regime"].isin(REGIMES).to_numpy()
    data = cases.loc[known].copy()
    missing = [t for t in grids.REGIME_TARGETS if t not in model.targets]
    if missing:
        raise ValueError(f"the regime map needs the surrogate to model {list(grids.REGIME_TARGETS)}; it lacks "
                         f"{missing} (config surrogate.targets, or a results table without those columns)")
    targets = list(grids.REGIME_TARGETS)
    at_cases = grids.regime_probabilities(grids.evaluate(model, data[list(design.NAMES)], targets, support), rules)
    for c in ("p_normal", "p_jamming", "p_short_feed"):
        data[c] = at_cases[c].to_numpy()
    data["regime_pred"] = most_probable(at_cases)
    data["h_over_d"] = h_over_d(data)
    axes = PLANE_SLICE.axes(ranges=ranges, sizes={"d_um": n_d, "h_um": n_h})
    frame = PLANE_SLICE.frame(axes, {"f": f, "v_mm_s": v_mm_s}, ranges)
    plane = grids.regime_probabilities(grids.evaluate(model, frame, targets, support), rules)
    cols = [c for c in ("case_id", "sweep", "index") if c in data] + list(design.NAMES) + [
        "h_over_d", "mfr", "pd", "regime", "p_normal", "p_jamming", "p_short_feed", "regime_pred"]
    if coarse_ratio(data) is not None:  # a size distribution: the feed's quantiles and h/D90 go with the cases
        cols += ["size_span", "feed_d50_um", "feed_d90_um", "h_over_d90"]
    return data[[c for c in cols if c in data]].reset_index(drop=True), plane


def draw_regime_overlay(data: pd.DataFrame, plane: pd.DataFrame, stem, excluded: int, support: dict,
                        floor: str | None = None) -> MapResult:
    """The figure from ``regime_tables``' two tables (or their CSVs read back); ``excluded``: the
    cases left out for want of a DEM regime (the title counts them). Saved with the cases' table."""
    counts = regime_counts(data["regime"].to_numpy(), data["regime_pred"].to_numpy())
    d, h = np.unique(plane["d_um"]), np.unique(plane["h_um"])
    shape = (len(d), len(h))  # d varies slowest
    ratio = coarse_ratio(data)  # D90 / D50 of a size distribution's feed; None: one size
    x_col, x_label = (("h_over_d90", "gap over the feed's D90, h/D90 [-] (a size distribution)") if ratio
                      else ("h_over_d", "gap to diameter ratio h/d [-]"))
    fig = new_figure(14.5, 5.8)
    ax0, ax1 = fig.subplots(1, 2)
    for r in REGIMES:
        m = (data["regime"] == r).to_numpy()
        ax0.scatter(data[x_col][m], data["v_mm_s"][m], c=COLOURS[r], marker=MARKERS[r], s=40,
                    edgecolor="white", lw=0.4, label=f"{NAMES_LONG[r]} ({int(m.sum())})", zorder=3)
    if ratio:
        ax0.axvline(1.0, color="k", lw=1, ls=":", zorder=1, label="h = D90")
    ax0.set_xlabel(x_label)
    ax0.set_ylabel(BY_NAME["v_mm_s"].label)
    ax0.set_title(f"DEM regimes of {len(data)} cases", fontsize=10)
    ax0.grid(alpha=0.3)
    ax0.legend(fontsize=8, loc="best")

    regime_idx = np.array([REGIMES.index(r) for r in most_probable(plane)]).reshape(shape)
    cmap = mcolors.ListedColormap([mcolors.to_rgba(COLOURS[r], 0.35) for r in REGIMES])
    ax1.pcolormesh(d, h, regime_idx.T, cmap=cmap, vmin=-0.5, vmax=2.5, shading="nearest")
    for col, name in (("p_jamming", "jamming"), ("p_short_feed", "short_feed")):
        P = plane[col].to_numpy().reshape(shape).T
        if P.max() >= 0.1 and P.min() <= 0.9:
            cs = ax1.contour(d, h, P, levels=[0.1, 0.5, 0.9], colors=COLOURS[name], linestyles=["--", "-", "--"],
                             linewidths=[1, 2, 1])
            ax1.clabel(cs, fmt=lambda p, n=name: f"P({NAMES_LONG[n]}) {p:.1f}", fontsize=7)
    ok = plane["supported"].to_numpy().reshape(shape).T
    if (~ok).any():
        ax1.contourf(d, h, (~ok).astype(float), levels=[0.5, 1.5], colors="none", hatches=["////"])
    ax1.plot(d, d, color="k", lw=1, ls=":")
    if ratio:
        ax1.plot(d, ratio * d, color="k", lw=1.2, ls="-.")
    ax1.set_ylim(h.min(), h.max())
    for r in REGIMES:
        m = (data["regime"] == r).to_numpy()
        ax1.scatter(data["d_um"][m], data["h_um"][m], c=COLOURS[r], marker=MARKERS[r], s=16, edgecolor="k",
                    lw=0.3, zorder=4)
    handles = [Line2D([], [], color=COLOURS["jamming"], lw=2, label="P(jamming) = 0.5 (dashed 0.1, 0.9)"),
               Line2D([], [], color=COLOURS["short_feed"], lw=2, label="P(short feed) = 0.5 (dashed 0.1, 0.9)"),
               Line2D([], [], color="k", ls=":", label="h = D50 (gap of one median particle)" if ratio
                      else "h = d (gap of one particle)"),
               *([Line2D([], [], color="k", ls="-.", lw=1.2, label=f"h = D90 ({ratio:.2f} x D50, the feed's)")]
                 if ratio else []),
               Line2D([], [], marker="o", ls="", color="0.4", ms=4, label="DEM cases (all f, v)")]
    ax1.legend(handles=handles, fontsize=7.5, loc="lower right", framealpha=0.9)
    ax1.set_xlabel("the powder's D50 [um]" if ratio else BY_NAME["d_um"].label)
    ax1.set_ylabel(BY_NAME["h_um"].label)
    ax1.set_title(f"Most probable regime of a new run at {slices.text(PLANE_SLICE.fixed_of(plane))} "
                  f"(shade), probability contours", fontsize=10)
    agree = int(counts["both"].sum())
    fig.suptitle(f"Regimes: the surrogate's most probable regime matches the DEM at {agree} of {len(data)} "
                 f"training cases; {int(excluded)} cases without a regime left out", fontsize=11)
    note = support_note(fig, plane["supported"].to_numpy(), support, "points of the (d, h) plane")
    paths = save_figure(fig, stem, data, floor)
    return MapResult(paths, data, {"counts": counts, "excluded": int(excluded), "agree": agree,
                                    "plane": plane, "note": note, "x": x_col, "coarse_ratio": ratio})
