"""Processing design maps drawn from a predictor (the surrogate) and from DEM cases.

Every function takes a predictor ``predict(points[n, 4]) -> [n, 2]`` (columns mfr, pd; points in
physical units, ``design.NAMES`` order) and/or a results DataFrame, draws one figure, and saves it
through :func:`save_figure` as ``<stem>.png``, ``<stem>.pdf`` and the numbers behind it as
``<stem>.csv``.  Fixed values and grid sizes are arguments (the workflow passes them from config);
defaults follow SPEC.md.

Figures
-------
* :func:`machine_map` -- MFR (x) against PD (y) for a grid of layer thickness h and blade speed v
  at fixed powder (f, d).  Each blade speed is a line through the h values; the area between
  two neighbouring speed lines is filled in the colour of the speed interval (colour bar), and
  lines of constant h cross them.  Every line carries its value at one end ("v = 6.1 mm/s" at
  the thick-layer end of the v lines, "h = 57 um" at the fast end of the h lines), so a setting
  is read at the crossing of an h line and a v line.
* :func:`powder_band_map` -- (a) at fixed h, v: MFR against d and PD against d, the band between
  the lowest and the highest friction filled and each friction line labelled; a third panel
  shows the same band in the MFR-PD plane (the machine-map plane), d marked along its edges.
  The against-d panels are the ones to read values from; the plane shows where the powder sits
  relative to the machine map.
* :func:`powder_cluster_map` -- (b) at fixed h, v: in the MFR-PD plane one cluster of points per
  diameter (colour, labelled "d = .. um"), the points of a cluster being the friction values
  (marker size grows with f; the low-f and high-f ends marked).
* :func:`parallel_coordinates` -- one polyline per case over the four parameters (each axis
  normalised to its design range, ticks in physical units), coloured by normalised MFR in the
  top panel and normalised PD in the bottom panel, the best case drawn thick and annotated.
* :func:`regime_overlay` -- DEM cases in the (h/d, v) plane coloured by their DEM regime, the
  same cases coloured by the regime the threshold rules give on the surrogate's prediction
  (disagreements ringed), and the MFR-PD plane with the threshold lines, DEM values and
  predictions.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib import colors as mcolors  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from spreadmap.design import BY_NAME, NAMES, bounds  # noqa: E402
from spreadmap.figures import save_figure  # noqa: E402
from spreadmap.metrics import classify  # noqa: E402
from spreadmap.table import usable  # noqa: E402

Predictor = Callable[[np.ndarray], np.ndarray]

REGIMES: tuple[str, ...] = ("normal", "jamming", "short_feed")
REGIME_COLOURS = {"normal": "tab:green", "jamming": "tab:red", "short_feed": "tab:orange"}
REGIME_MARKERS = {"normal": "o", "jamming": "X", "short_feed": "s"}
REGIME_LABELS = {"normal": "normal extrusion", "jamming": "jamming", "short_feed": "short feed"}

MFR_LABEL = "mass flow rate MFR [-]"
PD_LABEL = "packing density PD [-]"

__all__ = [
    "MapResult",
    "save_figure",
    "machine_map",
    "powder_band_map",
    "powder_cluster_map",
    "parallel_coordinates",
    "best_case",
    "usable_cases",
    "classify_regime",
    "regime_overlay",
]


@dataclass
class MapResult:
    """What a map function wrote: the three file paths, the table saved as CSV, and extras."""

    paths: dict[str, Path]
    data: pd.DataFrame
    best: pd.Series | None = None  # parallel_coordinates: the marked case
    counts: pd.DataFrame | None = None  # regime_overlay: cases per regime
    info: dict = field(default_factory=dict)


# --------------------------------------------------------------------------------------- helpers


def _predict(predict: Predictor, points: np.ndarray) -> np.ndarray:
    out = np.asarray(predict(np.asarray(points, float)), float)
    if out.shape != (len(points), 2):
        raise ValueError(f"predictor returned shape {out.shape}, expected ({len(points)}, 2)")
    return out


def _values(values, n: int, name: str, ranges: dict | None) -> np.ndarray:
    """Explicit values if given, else n values spanning the range of parameter ``name``."""
    if values is not None:
        v = np.asarray(values, float).ravel()
        if v.size == 0:
            raise ValueError(f"no values given for {name}")
        return v
    if n < 1:
        raise ValueError(f"grid size for {name} must be >= 1")
    low, high = bounds(ranges)
    i = NAMES.index(name)
    return np.linspace(low[i], high[i], n) if n > 1 else np.array([(low[i] + high[i]) / 2])


def _grid_frame(**columns) -> pd.DataFrame:
    """Full tensor grid of the given parameter values, NAMES order, first name varying slowest."""
    order = [n for n in NAMES if n in columns]
    mesh = np.meshgrid(*[np.atleast_1d(np.asarray(columns[n], float)) for n in order],
                       indexing="ij")
    return pd.DataFrame({n: m.ravel() for n, m in zip(order, mesh)})[list(NAMES)]


def _fmt(value: float, digits: int = 4) -> str:
    return f"{value:.{digits}g}"


def _set_limits(ax, x, y, pad: float = 0.08, pad_right: float | None = None,
                pad_top: float | None = None) -> None:
    x = np.asarray(x, float)[np.isfinite(x)]
    y = np.asarray(y, float)[np.isfinite(y)]
    if x.size == 0 or y.size == 0:
        return
    dx = max(np.ptp(x), 1e-3)
    dy = max(np.ptp(y), 1e-3)
    ax.set_xlim(x.min() - pad * dx, x.max() + (pad if pad_right is None else pad_right) * dx)
    ax.set_ylim(y.min() - pad * dy, y.max() + (pad if pad_top is None else pad_top) * dy)


def _end_label(ax, xs, ys, text, colour="black", at: str = "end", fontsize: float = 8,
               distance: float = 6.0, edge: str | None = None,
               placed: list | None = None) -> None:
    """Write ``text`` just beyond one end of the polyline (xs, ys), in the line's direction.

    With ``placed`` (a list shared by the labels of one axes) a label that would overlap one
    already placed is pushed further out along the line (then sideways) until it is free,
    and joined to its line end by a thin leader.  Call after the axes' size and limits are
    final (colour bars added, limits set).
    """
    xs = np.asarray(xs, float)
    ys = np.asarray(ys, float)
    if at == "start":
        xs, ys = xs[::-1], ys[::-1]
    x1, y1 = xs[-1], ys[-1]
    # direction in display space, from the previous point to the end point
    if len(xs) > 1:
        p0 = ax.transData.transform((xs[-2], ys[-2]))
        p1 = ax.transData.transform((x1, y1))
        d = p1 - p0
    else:
        d = np.array([1.0, 0.0])
    norm = np.hypot(*d)
    d = d / norm if norm > 0 else np.array([1.0, 0.0])
    ha = "left" if d[0] > 0.35 else ("right" if d[0] < -0.35 else "center")
    va = "bottom" if d[1] > 0.35 else ("top" if d[1] < -0.35 else "center")
    style = dict(textcoords="offset points", ha=ha, va=va, fontsize=fontsize, color=colour,
                 bbox=dict(boxstyle="round,pad=0.2", fc="white", ec=edge or "none", lw=1.2,
                           alpha=0.85),
                 zorder=6)
    first = tuple(distance * d)
    ann = ax.annotate(text, (x1, y1), xytext=first, **style)
    if placed is None:
        return
    renderer = ax.figure.canvas.get_renderer()
    perp = np.array([-d[1], d[0]])
    candidates = [np.array(first)]
    for extra in (12, 24, 36, 48, 60):
        for side in (0.0, 1.0, -1.0):
            candidates.append((distance + extra) * d + side * extra * 0.8 * perp)
    for off in candidates:
        ann.set_position(tuple(off))
        box = ann.get_window_extent(renderer).expanded(1.12, 1.25)
        if not any(box.overlaps(b) for b in placed):
            break
    else:  # nowhere free: keep the first position
        off = candidates[0]
        ann.set_position(first)
        box = ann.get_window_extent(renderer).expanded(1.12, 1.25)
    if not np.allclose(off, first):  # moved: redraw with a leader to the line end
        ann.remove()
        ax.annotate(text, (x1, y1), xytext=tuple(off),
                    arrowprops=dict(arrowstyle="-", color=edge or colour, lw=0.7, shrinkA=0,
                                    shrinkB=2),
                    **style)
    placed.append(box)


def _spread(values: np.ndarray, gap: float, low: float, high: float) -> np.ndarray:
    """Positions near ``values`` at least ``gap`` apart, kept inside [low, high] if they fit."""
    values = np.asarray(values, float)
    order = np.argsort(values)
    y = values[order].copy()
    for _ in range(3):
        for i in range(1, len(y)):
            y[i] = max(y[i], y[i - 1] + gap)
        if len(y) and y[-1] > high:
            y[-1] = high
            for i in range(len(y) - 2, -1, -1):
                y[i] = min(y[i], y[i + 1] - gap)
        if len(y) and y[0] < low:
            y[0] = low
    out = np.empty_like(y)
    out[order] = y
    return out


def _right_labels(ax, x_end: float, ys, texts, colours, fontsize: float = 8) -> None:
    """Label curves at their right end x_end, labels spread vertically so they never overlap,
    each joined to its curve end by a thin leader.  Call after the y limits are final."""
    y0, y1 = ax.get_ylim()
    x0, x1 = ax.get_xlim()
    gap = 0.055 * (y1 - y0) * fontsize / 8
    ys = np.asarray(ys, float)
    pos = _spread(ys, gap, y0 + 0.5 * gap, y1 - 0.5 * gap)
    xt = x_end + 0.04 * (x1 - x0)
    for y, yt, text, c in zip(ys, pos, texts, colours):
        ax.annotate(text, (x_end, y), xytext=(xt, yt), textcoords="data", ha="left",
                    va="center", fontsize=fontsize, color=c, zorder=6,
                    arrowprops=dict(arrowstyle="-", color=c, lw=0.6, shrinkA=0, shrinkB=1))


def _which_labelled(n: int, max_labels: int) -> set[int]:
    """Indices of the lines that get a label: all if few, else every k-th from the first, and
    the last, with k the smallest step that keeps the count within ``max_labels``."""
    if n <= max_labels:
        return set(range(n))
    step = int(np.ceil((n - 1) / max(max_labels - 1, 1)))
    return set(range(0, n, step)) | {n - 1}


def usable_cases(cases: pd.DataFrame) -> pd.DataFrame:
    """Cases fit for statistics: status ok, not flagged, finite MFR and PD (where present)."""
    keep = usable(cases)
    for t in ("mfr", "pd"):
        if t in cases:
            keep &= np.isfinite(cases[t].to_numpy(float))
    return cases.loc[keep]


# --------------------------------------------------------------------------------- machine map


def machine_map(
    predict: Predictor,
    path_stem,
    f: float = 0.45,
    d_um: float = 45.0,
    n_h: int = 5,
    n_v: int = 5,
    h_values: Sequence[float] | None = None,
    v_values: Sequence[float] | None = None,
    ranges: dict | None = None,
    max_labels: int = 7,
) -> MapResult:
    """Machine map: MFR (x) against PD (y) over an h x v grid at fixed friction f and diameter d.

    Grid: ``n_h`` layer thicknesses and ``n_v`` blade speeds spanning their ranges (end points
    included), or the explicit ``h_values`` / ``v_values``.  The CSV holds the full grid, one row
    per (h, v), columns f, d_um, h_um, v_mm_s, mfr, pd, h varying slowest.  With more than
    ``max_labels`` lines of one kind only ``max_labels`` of them (both ends included) carry a
    label; the others are drawn thinner (the bands' colour still gives v).
    """
    h = _values(h_values, n_h, "h_um", ranges)
    v = _values(v_values, n_v, "v_mm_s", ranges)
    grid = _grid_frame(f=f, d_um=d_um, h_um=h, v_mm_s=v)
    y = _predict(predict, grid[list(NAMES)].to_numpy())
    grid["mfr"], grid["pd"] = y[:, 0], y[:, 1]
    mfr = y[:, 0].reshape(len(h), len(v))
    pdv = y[:, 1].reshape(len(h), len(v))

    fig, ax = plt.subplots(figsize=(8.2, 6.2))
    # room around the grid for the end labels
    _set_limits(ax, mfr, pdv, pad=0.1, pad_right=0.24, pad_top=0.12)
    cmap = plt.get_cmap("viridis")
    vnorm = mcolors.Normalize(v.min(), v.max()) if len(v) > 1 else mcolors.Normalize(
        v[0] - 1, v[0] + 1)
    vorder = np.argsort(v)
    horder = np.argsort(h)

    # bands of constant v: between neighbouring v lines, coloured by the interval's mid speed
    for a, b in zip(vorder[:-1], vorder[1:]):
        xs = np.concatenate([mfr[horder, a], mfr[horder[::-1], b]])
        ys = np.concatenate([pdv[horder, a], pdv[horder[::-1], b]])
        ax.fill(xs, ys, color=cmap(vnorm((v[a] + v[b]) / 2)), alpha=0.35, lw=0, zorder=1)

    v_lab = _which_labelled(len(v), max_labels)
    h_lab = _which_labelled(len(h), max_labels)
    for k, j in enumerate(vorder):
        lw = 2.2 if k in v_lab else 1.0
        ax.plot(mfr[horder, j], pdv[horder, j], color=cmap(vnorm(v[j])), lw=lw, zorder=3)
    for k, i in enumerate(horder):
        lw = 1.3 if k in h_lab else 0.6
        ax.plot(mfr[i, vorder], pdv[i, vorder], color="0.15", lw=lw, ls="--", zorder=4)
    ax.scatter(mfr.ravel(), pdv.ravel(), s=12, color="black", zorder=5)

    sm = plt.cm.ScalarMappable(norm=vnorm, cmap=cmap)
    cb = fig.colorbar(sm, ax=ax, pad=0.02)
    cb.set_label(BY_NAME["v_mm_s"].label + "  (bands between neighbouring v lines)")
    cb.set_ticks(np.sort(v) if len(v) <= 12 else np.linspace(v.min(), v.max(), 6))

    placed: list = []  # label boxes, so that later labels avoid earlier ones
    for k, j in enumerate(vorder):  # v labels at the thick-layer (largest h) end
        if k in v_lab:
            _end_label(ax, mfr[horder, j], pdv[horder, j], f"v = {_fmt(v[j])} mm/s",
                       edge=mcolors.to_hex(cmap(vnorm(v[j]))), placed=placed)
    for k, i in enumerate(horder):  # h labels at the fast (largest v) end
        if k in h_lab and len(v) > 1:
            _end_label(ax, mfr[i, vorder], pdv[i, vorder], f"h = {_fmt(h[i])} um",
                       colour="0.1", edge="0.3", placed=placed)
        elif k in h_lab:
            ax.annotate(f"h = {_fmt(h[i])} um", (mfr[i, 0], pdv[i, 0]), xytext=(5, -10),
                        textcoords="offset points", fontsize=8)
    handles = [
        Line2D([], [], color=cmap(0.6), lw=2.2, label="constant blade speed v (solid)"),
        Line2D([], [], color="0.15", lw=1.3, ls="--", label="constant layer thickness h (dashed)"),
        Line2D([], [], color="black", marker="o", ls="", ms=4, label="grid setting (h, v)"),
    ]
    ax.legend(handles=handles, loc="lower right", fontsize=8, framealpha=0.9)
    ax.set_xlabel(MFR_LABEL)
    ax.set_ylabel(PD_LABEL)
    ax.set_title(f"Machine map: powder f = {_fmt(f)}, d = {_fmt(d_um)} um\n"
                 f"h {_fmt(h.min())}-{_fmt(h.max())} um ({len(h)} values), "
                 f"v {_fmt(v.min())}-{_fmt(v.max())} mm/s ({len(v)} values)", fontsize=10)
    ax.grid(alpha=0.3)
    paths = save_figure(fig, path_stem, grid)
    return MapResult(paths=paths, data=grid)


# --------------------------------------------------------------------------------- powder maps


def powder_band_map(
    predict: Predictor,
    path_stem,
    h_um: float = 57.0,
    v_mm_s: float = 6.1,
    n_d: int = 41,
    n_f: int = 5,
    d_values: Sequence[float] | None = None,
    f_values: Sequence[float] | None = None,
    ranges: dict | None = None,
) -> MapResult:
    """Powder map (a): the band between the lowest and the highest friction as d varies.

    Layout: MFR against d and PD against d (the panels to read values from), band between the
    lowest- and highest-friction curves filled, every friction curve drawn and labelled; third
    panel: the same band in the MFR-PD plane of the machine map, with d marked along its edges.
    CSV: the full d x f grid (columns f, d_um, h_um, v_mm_s, mfr, pd; f varying slowest).
    """
    d = np.sort(_values(d_values, n_d, "d_um", ranges))
    fv = np.sort(_values(f_values, n_f, "f", ranges))
    grid = _grid_frame(f=fv, d_um=d, h_um=h_um, v_mm_s=v_mm_s)
    y = _predict(predict, grid[list(NAMES)].to_numpy())
    grid["mfr"], grid["pd"] = y[:, 0], y[:, 1]
    mfr = y[:, 0].reshape(len(fv), len(d))
    pdv = y[:, 1].reshape(len(fv), len(d))

    cmap = plt.get_cmap("plasma")
    fnorm = mcolors.Normalize(fv.min(), fv.max() if len(fv) > 1 else fv.min() + 1)
    fcol = [cmap(0.8 * fnorm(x)) for x in fv]  # stay off plasma's pale yellow end
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8))
    for ax, z, lab in ((axes[0], mfr, MFR_LABEL), (axes[1], pdv, PD_LABEL)):
        ax.fill_between(d, z[0], z[-1], color="tab:blue", alpha=0.18, lw=0,
                        label=f"band f = {_fmt(fv[0])} to {_fmt(fv[-1])}")
        for k in range(len(fv)):
            edge = k in (0, len(fv) - 1)
            ax.plot(d, z[k], color=fcol[k], lw=2.2 if edge else 1.0, ls="-" if edge else ":")
        ax.set_xlabel(BY_NAME["d_um"].label)
        ax.set_ylabel(lab)
        ax.set_xlim(d.min(), d.max() + 0.22 * np.ptp(d) if len(d) > 1 else d.max() + 1)
        _set_limits(ax, d, z, pad=0.06)
        ax.set_xlim(d.min(), d.max() + 0.22 * np.ptp(d) if len(d) > 1 else d.max() + 1)
        _right_labels(ax, d[-1], z[:, -1], [f"f = {_fmt(x)}" for x in fv], fcol)
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[0].set_title("MFR against particle diameter", fontsize=10)
    axes[1].set_title("PD against particle diameter", fontsize=10)

    ax = axes[2]
    _set_limits(ax, mfr, pdv, pad=0.1, pad_right=0.18, pad_top=0.15)
    ax.fill(np.concatenate([mfr[0], mfr[-1][::-1]]), np.concatenate([pdv[0], pdv[-1][::-1]]),
            color="tab:blue", alpha=0.18, lw=0)
    marks = np.unique(np.round(np.linspace(0, len(d) - 1, min(5, len(d)))).astype(int))
    for k in (0, len(fv) - 1):
        ax.plot(mfr[k], pdv[k], color=fcol[k], lw=2.2, label=f"f = {_fmt(fv[k])} (d varies)")
        ax.scatter(mfr[k, marks], pdv[k, marks], color=fcol[k], s=18, zorder=4)
    for m in marks:  # d ticks: join the two edges at the same d
        ax.plot([mfr[0, m], mfr[-1, m]], [pdv[0, m], pdv[-1, m]], color="0.4", lw=0.7, ls="--")
        ax.annotate(f"d = {_fmt(d[m])} um", (mfr[-1, m], pdv[-1, m]), xytext=(4, 4),
                    textcoords="offset points", fontsize=7, color="0.2",
                    bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))
    ax.set_xlabel(MFR_LABEL)
    ax.set_ylabel(PD_LABEL)
    ax.set_title("Friction band in the machine-map plane", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.suptitle(f"Powder map (a): band between friction f = {_fmt(fv[0])} and "
                 f"{_fmt(fv[-1])} as diameter varies, at h = {_fmt(h_um)} um, "
                 f"v = {_fmt(v_mm_s)} mm/s", fontsize=11)
    fig.tight_layout()
    paths = save_figure(fig, path_stem, grid)
    return MapResult(paths=paths, data=grid)


def powder_cluster_map(
    predict: Predictor,
    path_stem,
    h_um: float = 57.0,
    v_mm_s: float = 6.1,
    n_d: int = 5,
    n_f: int = 7,
    d_values: Sequence[float] | None = None,
    f_values: Sequence[float] | None = None,
    ranges: dict | None = None,
) -> MapResult:
    """Powder map (b): in the MFR-PD plane, one cluster per diameter d, its points the frictions.

    Colour = d (labelled next to each cluster), marker size grows with f, the points of a
    cluster joined in order of f; the lowest- and highest-friction points are drawn as open
    triangle / filled square.  CSV: the full d x f grid (f varying slowest).
    """
    d = np.sort(_values(d_values, n_d, "d_um", ranges))
    fv = np.sort(_values(f_values, n_f, "f", ranges))
    grid = _grid_frame(f=fv, d_um=d, h_um=h_um, v_mm_s=v_mm_s)
    y = _predict(predict, grid[list(NAMES)].to_numpy())
    grid["mfr"], grid["pd"] = y[:, 0], y[:, 1]
    mfr = y[:, 0].reshape(len(fv), len(d))
    pdv = y[:, 1].reshape(len(fv), len(d))

    # viridis without its pale yellow end, which is hard to read on white
    cmap = mcolors.LinearSegmentedColormap.from_list(
        "viridis_dark", plt.get_cmap("viridis")(np.linspace(0.0, 0.9, 256)))
    dnorm = mcolors.Normalize(d.min(), d.max() if len(d) > 1 else d.min() + 1)
    sizes = 15 + 85 * ((fv - fv.min()) / (np.ptp(fv) if np.ptp(fv) > 0 else 1.0))
    fig, ax = plt.subplots(figsize=(8.2, 6.2))
    _set_limits(ax, mfr, pdv, pad=0.1, pad_right=0.22, pad_top=0.12)
    cb = fig.colorbar(plt.cm.ScalarMappable(norm=dnorm, cmap=cmap), ax=ax, pad=0.02)
    cb.set_label(BY_NAME["d_um"].label)
    cb.set_ticks(d if len(d) <= 12 else np.linspace(d.min(), d.max(), 6))
    placed: list = []
    for j in range(len(d)):
        c = cmap(dnorm(d[j]))
        ax.plot(mfr[:, j], pdv[:, j], color=c, lw=1.0, alpha=0.8, zorder=2)
        ax.scatter(mfr[:, j], pdv[:, j], s=sizes, color=c, edgecolor="black", lw=0.4, zorder=3)
        ax.scatter(mfr[0, j], pdv[0, j], s=70, marker="^", facecolor="white", edgecolor=c,
                   lw=1.6, zorder=4)
        ax.scatter(mfr[-1, j], pdv[-1, j], s=70, marker="s", color=c, edgecolor="black",
                   lw=0.8, zorder=4)
        # label just beyond the cluster's low-friction end, along the cluster's direction
        _end_label(ax, mfr[:, j], pdv[:, j], f"d = {_fmt(d[j])} um", at="start",
                   fontsize=9, distance=10, edge=mcolors.to_hex(c), placed=placed)
    handles = [
        Line2D([], [], marker="^", ls="", mfc="white", mec="0.2", ms=8,
               label=f"lowest friction f = {_fmt(fv[0])}"),
        Line2D([], [], marker="s", ls="", color="0.3", mec="black", ms=7,
               label=f"highest friction f = {_fmt(fv[-1])}"),
        Line2D([], [], marker="o", ls="-", color="0.5", mec="black", ms=5,
               label=f"{len(fv)} friction values, marker size grows with f"),
    ]
    ax.legend(handles=handles, loc="best", fontsize=8, framealpha=0.9)
    ax.set_xlabel(MFR_LABEL)
    ax.set_ylabel(PD_LABEL)
    ax.set_title(f"Powder map (b): clusters of constant diameter as friction varies "
                 f"({_fmt(fv[0])}-{_fmt(fv[-1])})\nat h = {_fmt(h_um)} um, "
                 f"v = {_fmt(v_mm_s)} mm/s", fontsize=10)
    ax.grid(alpha=0.3)
    paths = save_figure(fig, path_stem, grid)
    return MapResult(paths=paths, data=grid)


# ------------------------------------------------------------------------ parallel coordinates


def best_case(
    cases: pd.DataFrame,
    mfr_min: float = 0.0,
    score: Callable[[pd.DataFrame], np.ndarray] | None = None,
) -> pd.Series:
    """The best case of a table of (usable) cases.

    Default rule: the highest PD among the cases with MFR >= ``mfr_min`` (a dense layer from a
    setting that still flows).  With ``score`` given, the case with the highest
    ``score(cases)`` among those same cases.  Raises ValueError if no case qualifies.
    """
    ok = cases[cases["mfr"].to_numpy(float) >= mfr_min]
    if ok.empty:
        raise ValueError(f"no case has MFR >= {mfr_min}")
    value = np.asarray(score(ok), float) if score is not None else ok["pd"].to_numpy(float)
    if not np.isfinite(value).any():
        raise ValueError("no finite score")
    return ok.iloc[int(np.nanargmax(value))]


def parallel_coordinates(
    cases: pd.DataFrame,
    path_stem,
    mfr_min: float = 0.0,
    score: Callable[[pd.DataFrame], np.ndarray] | None = None,
    ranges: dict | None = None,
    n_ticks: int = 5,
) -> MapResult:
    """Parallel coordinates of a sample of DEM cases (the converged LDS sample).

    Only usable cases (status ok, not flagged, finite MFR and PD) are drawn.  Axes: the four
    parameters, each normalised to its design range (``design.bounds(ranges)``) and ticked in
    physical units.  Top panel coloured by normalised MFR, bottom by normalised PD (min-max over
    the drawn cases; the colour bars give the physical values too).  The best case (see
    :func:`best_case`: ``mfr_min`` and ``score``) is drawn thick red and annotated.  CSV: the
    drawn cases with their normalised values and a boolean column ``best``.
    """
    data = usable_cases(cases).copy()
    if data.empty:
        raise ValueError("no usable case to draw")
    best = best_case(data, mfr_min=mfr_min, score=score)
    low, high = bounds(ranges)
    x = (data[list(NAMES)].to_numpy(float) - low) / (high - low)
    for k, n in enumerate(NAMES):
        data[f"{n}_norm"] = x[:, k]
    for t in ("mfr", "pd"):
        z = data[t].to_numpy(float)
        span = np.ptp(z)
        data[f"{t}_norm"] = (z - z.min()) / span if span > 0 else 0.5
    data["best"] = data.index == best.name
    xb = (best[list(NAMES)].to_numpy(float) - low) / (high - low)

    xpos = np.arange(len(NAMES), dtype=float)
    fig, axes = plt.subplots(2, 1, figsize=(12, 8.5), sharex=True)
    cmap = plt.get_cmap("viridis")
    for ax, t, name in ((axes[0], "mfr", "MFR"), (axes[1], "pd", "PD")):
        c = data[f"{t}_norm"].to_numpy(float)
        order = np.argsort(c)  # high values drawn last, on top
        segs = [np.column_stack([xpos, row]) for row in x[order]]
        alpha = float(np.clip(8.0 / np.sqrt(len(data)), 0.15, 0.9))
        lc = LineCollection(segs, cmap=cmap, norm=mcolors.Normalize(0, 1), lw=1.0, alpha=alpha)
        lc.set_array(c[order])
        ax.add_collection(lc)
        ax.plot(xpos, xb, color="white", lw=5.5, zorder=5)
        ax.plot(xpos, xb, color="tab:red", lw=3.0, marker="o", ms=7, zorder=6,
                label="best case")
        for k, n in enumerate(NAMES):
            ax.axvline(xpos[k], color="0.2", lw=1.0, zorder=3)
            for tv in np.linspace(0, 1, n_ticks):
                phys = low[k] + tv * (high[k] - low[k])
                ax.plot([xpos[k] - 0.02, xpos[k]], [tv, tv], color="0.2", lw=1.0, zorder=3)
                ax.text(xpos[k] - 0.03, tv, _fmt(phys), ha="right", va="center", fontsize=8,
                        bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7),
                        zorder=4)
        z = data[t].to_numpy(float)
        cb = fig.colorbar(plt.cm.ScalarMappable(norm=mcolors.Normalize(0, 1), cmap=cmap), ax=ax,
                          pad=0.02)
        cb.set_label(f"normalised {name} [-]\n(0 = {z.min():.3f}, 1 = {z.max():.3f})")
        ax.set_ylim(-0.06, 1.06)
        ax.set_yticks([])
        ax.set_xlim(-0.35, len(NAMES) - 1 + 1.25)  # right margin holds the best-case box
        ax.set_title(f"Cases coloured by normalised {name}", fontsize=10)
        text = (f"best case{': ' + str(best['case_id']) if 'case_id' in best else ''}\n"
                f"f = {best['f']:.3g}, d = {best['d_um']:.3g} um\n"
                f"h = {best['h_um']:.3g} um, v = {best['v_mm_s']:.3g} mm/s\n"
                f"MFR = {best['mfr']:.3f}, PD = {best['pd']:.3f}")
        ax.annotate(text, (xpos[-1], xb[-1]), xytext=(xpos[-1] + 0.2, 0.5), textcoords="data",
                    va="center", ha="left", fontsize=8.5, zorder=7,
                    bbox=dict(boxstyle="round", fc="white",
                              ec="tab:red", alpha=0.95),
                    arrowprops=dict(arrowstyle="-", color="tab:red"))
    axes[1].set_xticks(xpos, [BY_NAME[n].label for n in NAMES])
    rule = ("highest score" if score is not None else "highest PD") + (
        f" among cases with MFR >= {mfr_min:g}" if mfr_min > 0 else "")
    fig.suptitle(f"Parallel coordinates of {len(data)} DEM cases; best case = {rule}",
                 fontsize=11)
    fig.tight_layout()
    cols = [c for c in ("case_id", "sweep", "index") if c in data] + list(NAMES) + [
        "mfr", "pd"] + [f"{n}_norm" for n in NAMES] + ["mfr_norm", "pd_norm", "best"]
    table = data[cols].reset_index(drop=True)
    paths = save_figure(fig, path_stem, table)
    return MapResult(paths=paths, data=table, best=best)


# ------------------------------------------------------------------------------- regime overlay


def classify_regime(mfr, pd_, jam_mfr_max: float, short_feed_pd_min: float) -> np.ndarray:
    """The DEM cases' rule (:func:`spreadmap.metrics.classify`: jamming if MFR < jam_mfr_max,
    else short feed if PD < short_feed_pd_min, else normal) on arrays of predictions. A prediction
    has no layer-density scatter, so the rule's scatter bound imposes nothing here."""
    rules = {"jam_mfr_max": jam_mfr_max, "short_feed_pd_min": short_feed_pd_min, "short_feed_cv_max": np.inf}
    return np.vectorize(lambda m, p: classify(m, p, 0.0, rules), otypes=[object])(
        np.asarray(mfr, float), np.asarray(pd_, float))


def regime_overlay(
    cases: pd.DataFrame,
    predict: Predictor,
    path_stem,
    jam_mfr_max: float,
    short_feed_pd_min: float,
) -> MapResult:
    """Where the DEM cases of each regime fall, and where the surrogate's thresholds put them.

    Cases: rows with a ``regime`` in normal / jamming / short_feed (other rows -- failed or
    unclassified runs -- are left out and counted in ``info["excluded"]``).  The surrogate
    regime of a case is :func:`classify_regime` applied to ``predict`` at its parameters.

    Panels: (1) (h/d, v) plane coloured by DEM regime; (2) the same plane coloured by surrogate
    regime, cases where the two disagree ringed in black; (3) the MFR-PD plane with the threshold
    lines and regions, DEM values (filled, DEM regime) joined to the surrogate's predictions
    (open).  ``counts``: rows = regimes, columns ``dem``, ``surrogate``, ``both`` (cases with
    that regime in both).  CSV: one row per case drawn.
    """
    known = cases["regime"].isin(REGIMES).to_numpy()
    data = cases.loc[known].copy()
    excluded = int((~known).sum())
    if not data.empty:
        pred = _predict(predict, data[list(NAMES)].to_numpy(float))
    else:
        pred = np.empty((0, 2))
    data["mfr_pred"], data["pd_pred"] = pred[:, 0], pred[:, 1]
    data["regime_pred"] = classify_regime(pred[:, 0], pred[:, 1], jam_mfr_max,
                                          short_feed_pd_min)
    data["h_over_d"] = data["h_um"].to_numpy(float) / data["d_um"].to_numpy(float)
    data["agree"] = data["regime"].to_numpy() == data["regime_pred"].to_numpy()
    if "mfr" not in data:
        data["mfr"] = np.nan
    if "pd" not in data:
        data["pd"] = np.nan

    counts = pd.DataFrame({
        "dem": [int((data["regime"] == r).sum()) for r in REGIMES],
        "surrogate": [int((data["regime_pred"] == r).sum()) for r in REGIMES],
        "both": [int(((data["regime"] == r) & (data["regime_pred"] == r)).sum())
                 for r in REGIMES],
    }, index=pd.Index(REGIMES, name="regime"))

    fig, axes = plt.subplots(1, 3, figsize=(17, 5.4))
    hd, vv = data["h_over_d"].to_numpy(float), data["v_mm_s"].to_numpy(float)
    for ax, col, title in ((axes[0], "regime", "DEM regime"),
                           (axes[1], "regime_pred", "Surrogate regime (threshold rules)")):
        for r in REGIMES:
            m = (data[col] == r).to_numpy()
            ax.scatter(hd[m], vv[m], c=REGIME_COLOURS[r], marker=REGIME_MARKERS[r], s=38,
                       edgecolor="white", lw=0.4,
                       label=f"{REGIME_LABELS[r]} ({int(m.sum())})", zorder=3)
        ax.set_xlabel("gap to diameter ratio h/d [-]")
        ax.set_ylabel(BY_NAME["v_mm_s"].label)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
    bad = ~data["agree"].to_numpy()
    axes[1].scatter(hd[bad], vv[bad], s=140, facecolor="none", edgecolor="black", lw=1.2,
                    label=f"disagrees with DEM ({int(bad.sum())})", zorder=4)
    for ax in axes[:2]:
        ax.legend(loc="best", fontsize=8, framealpha=0.9)

    ax = axes[2]
    xs = np.concatenate([data["mfr"].to_numpy(float), pred[:, 0], [jam_mfr_max]])
    ys = np.concatenate([data["pd"].to_numpy(float), pred[:, 1], [short_feed_pd_min]])
    _set_limits(ax, xs, ys, pad=0.08)
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    ax.axvspan(x0, jam_mfr_max, color=REGIME_COLOURS["jamming"], alpha=0.10, lw=0)
    ax.fill_between([jam_mfr_max, x1], y0, short_feed_pd_min, color=REGIME_COLOURS["short_feed"],
                    alpha=0.10, lw=0)
    ax.axvline(jam_mfr_max, color=REGIME_COLOURS["jamming"], ls="--", lw=1.2)
    ax.plot([jam_mfr_max, x1], [short_feed_pd_min] * 2, color=REGIME_COLOURS["short_feed"],
            ls="--", lw=1.2)
    ax.text(jam_mfr_max, y0 + 0.02 * (y1 - y0), f"jamming if MFR < {jam_mfr_max:g} ",
            va="bottom", ha="right", rotation=90, fontsize=8, color=REGIME_COLOURS["jamming"],
            bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))
    ax.text(x1, short_feed_pd_min, f"short feed if PD < {short_feed_pd_min:g} ", va="bottom",
            ha="right", fontsize=8, color=REGIME_COLOURS["short_feed"],
            bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    has = np.isfinite(data["mfr"].to_numpy(float)) & np.isfinite(data["pd"].to_numpy(float))
    ax.add_collection(LineCollection(
        [[(a, b), (c, e)] for a, b, c, e in zip(data["mfr"][has], data["pd"][has],
                                                pred[has, 0], pred[has, 1])],
        color="0.6", lw=0.6, zorder=2))
    for r in REGIMES:
        m = (data["regime"] == r).to_numpy()
        ax.scatter(data["mfr"][m & has], data["pd"][m & has], c=REGIME_COLOURS[r],
                   marker=REGIME_MARKERS[r], s=38, edgecolor="white", lw=0.4, zorder=3,
                   label=f"DEM: {REGIME_LABELS[r]}")
        if REGIME_MARKERS[r] == "X":  # open version of the filled X is the line marker x
            style = dict(marker="x", c=REGIME_COLOURS[r])
        else:
            style = dict(marker=REGIME_MARKERS[r], facecolor="none", edgecolor=REGIME_COLOURS[r])
        ax.scatter(pred[m, 0], pred[m, 1], s=30, lw=1.0, zorder=3, **style)
    ax.scatter([], [], facecolor="none", edgecolor="0.3", marker="o", s=30,
               label="surrogate prediction (open, colour = DEM regime),\n"
                     "joined to its DEM value")
    ax.set_xlabel(MFR_LABEL)
    ax.set_ylabel(PD_LABEL)
    ax.set_title("MFR-PD plane: DEM values and surrogate predictions", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=7.5, framealpha=0.9)

    n = len(data)
    agree = int(data["agree"].sum())
    fig.suptitle(f"Regimes of {n} DEM cases: surrogate thresholds agree on {agree}/{n}"
                 + (f" ({excluded} case{'s' if excluded > 1 else ''} without a regime left out)"
                    if excluded else ""),
                 fontsize=11)
    fig.tight_layout()
    cols = [c for c in ("case_id", "sweep", "index") if c in data] + list(NAMES) + [
        "h_over_d", "mfr", "pd", "regime", "mfr_pred", "pd_pred", "regime_pred", "agree"]
    table = data[cols].reset_index(drop=True)
    paths = save_figure(fig, path_stem, table)
    return MapResult(paths=paths, data=table, counts=counts,
                     info={"excluded": excluded, "agree": agree, "n": n})
