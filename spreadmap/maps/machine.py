"""Machine map: MFR (x) against a layer-quality measure (y) over a grid of layer thickness h and
blade speed v, at fixed powder (f, d).

Each blade speed is a line through the h values and the area between neighbouring speed lines is
filled in the colour of the interval; dashed lines join constant h. Uncertainty: an ellipse of one
model SD (x and y) around every grid setting, and a cross showing one DEM run's noise SD, so a
trend smaller than the ellipses is not resolved. Settings beyond the data have open marks, the
cells they touch are hatched, and the figure says how many there are.
"""
from __future__ import annotations

import matplotlib
import numpy as np
import pandas as pd
from matplotlib import colors as mcolors
from matplotlib.lines import Line2D
from matplotlib.patches import Ellipse, Polygon

from .. import slices
from ..design import BY_NAME
from ..figures import new_figure, save_figure
from ..targets import axis_label, definition, short
from . import grids
from .labels import end_label, which_labelled
from .style import HATCH, MapResult, fmt, set_limits, support_note, with_model_note

MACHINE = grids.MAP_DEFAULTS["machine"]
MACHINE_SLICE = slices.MACHINE  # h x v at fixed powder: the one definition, spreadmap.slices


def machine_map(model, stem, y: str = "pd", f: float = MACHINE["f"], d_um: float = MACHINE["d_um"],
                n_h: int = MACHINE["n_h"], n_v: int = MACHINE["n_v"],
                h_values=None, v_values=None, ranges=None, support=None, max_labels: int = 7,
                y_note: str | None = None, floor: str | None = None, model_note: str | None = None) -> MapResult:
    """Machine map: MFR (x) against a layer-quality measure y over a grid of h and v, at fixed powder (f, d).

    The grid is evaluated on the surrogate (``grids.evaluate``) and drawn as the module docstring
    says: a line per blade speed, dashed lines of constant h, an ellipse of one model SD around every
    setting, a cross of one DEM run's noise SD, settings beyond the data open and the cells they
    touch hatched.

    Parameters
    ----------
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate (``load_model``); it must model ``mfr`` and ``y``.
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv``.
    y : str, optional
        The target on the y axis (a layer-quality target or ``pd``).
    f : float, optional
        Friction coefficient [-]; default: the schema's ``maps.machine.f``.
    d_um : float, optional
        Particle diameter [um]; default: the schema's ``maps.machine.d_um``.
    n_h, n_v : int, optional
        Grid sizes of the layer thickness h and the blade speed v, each spanning its range (ends
        included; at least 2); default: the schema's ``maps.machine``.
    h_values : array_like or None, optional
        Explicit h values [um] instead of ``n_h`` (sorted); None: ``n_h`` over the range.
    v_values : array_like or None, optional
        Explicit v values [mm/s] instead of ``n_v`` (sorted); None: ``n_v`` over the range.
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.
    support : dict or None, optional
        The config's ``maps.support`` (``max_distance``, ``max_sd_ratio``); None: the schema's.
    max_labels : int, optional
        How many v lines and how many h lines get a label at most (``labels.which_labelled``).
    y_note : str or None, optional
        A note on y written in the axes' corner (how far it is from MFR in disguise); None: none.
    floor : str or None, optional
        The floor the cases ran on (``spreadmap.case.substrate.floor_label``), named on the figure
        and in the CSV.
    model_note : str or None, optional
        A line under the title naming the model drawn and its validation
        (``validation_note.validation_note``); None: none.

    Returns
    -------
    MapResult
        ``paths`` (``png``, ``pdf``, ``csv``), ``data``: the evaluated grid (h varying slowest,
        then v), and ``info``: ``y``, ``note`` (the support note), ``title`` and
        ``n_unsupported`` (settings beyond the data).

    Raises
    ------
    ValueError
        If explicit h or v values are empty, or a grid size is below 2 (``grids.values``).
    """
    support = support or grids.MAP_DEFAULTS["support"]
    grid = machine_grid(model, y, f, d_um, n_h, n_v, h_values, v_values, ranges, support)
    return draw_machine_map(grid, stem, y, support, max_labels, y_note, floor, model_note)


def machine_grid(model, y: str = "pd", f: float = MACHINE["f"], d_um: float = MACHINE["d_um"],
                 n_h: int = MACHINE["n_h"], n_v: int = MACHINE["n_v"], h_values=None, v_values=None,
                 ranges=None, support=None) -> pd.DataFrame:
    """The numbers of the machine map: the (h, v) grid at powder (f, d) evaluated for MFR and y.

    Parameters
    ----------
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate; it must model ``mfr`` and ``y``.
    y : str, optional
        The target on the map's y axis.
    f : float, optional
        Friction coefficient [-].
    d_um : float, optional
        Particle diameter [um].
    n_h, n_v : int, optional
        Grid sizes of h and v over their ranges (ends included; at least 2).
    h_values, v_values : array_like or None, optional
        Explicit h [um] and v [mm/s] values instead of ``n_h`` and ``n_v``.
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.
    support : dict or None, optional
        The config's ``maps.support``; None: the schema's.

    Returns
    -------
    pandas.DataFrame
        ``grids.evaluate``'s table, h varying slowest, then v: the four parameters, per target its
        mean, model SD and noise SD, and ``supported``.
    """
    support = support or grids.MAP_DEFAULTS["support"]
    axes = MACHINE_SLICE.axes(ranges=ranges, sizes={"h_um": n_h, "v_mm_s": n_v},
                              given={"h_um": h_values, "v_mm_s": v_values})
    frame = MACHINE_SLICE.frame(axes, {"f": f, "d_um": d_um}, ranges)
    return grids.evaluate(model, frame, ["mfr", y], support)


# where the noise cross may go (axes fractions of its left end; its note runs ~0.35 to the right)
CORNERS = ((0.08, 0.9), (0.08, 0.1), (0.5, 0.9), (0.5, 0.1))


def emptiest_corner(ax, xs, ys) -> tuple[float, float]:
    """The corner of CORNERS whose box (the cross and its note: 0.45 wide, 0.2 high, in axes
    fractions) holds the fewest of the map's points; the first of the emptiest on a tie."""
    pts = ax.transAxes.inverted().transform(ax.transData.transform(np.column_stack([xs, ys])))
    def count(corner):
        fx, fy = corner
        return int(np.sum((pts[:, 0] > fx - 0.06) & (pts[:, 0] < fx + 0.4) & (np.abs(pts[:, 1] - fy) < 0.1)))
    return min(CORNERS, key=count)


def draw_machine_map(grid, stem, y, support, max_labels=7, y_note=None, floor=None,
                     model_note=None) -> MapResult:
    """The machine map from ``machine_grid``'s table (or its CSV read back): its h and v values and
    its fixed powder read from the table; saved with that table (the arguments as ``machine_map``
    takes them)."""
    h, v = (np.unique(grid[n]) for n in MACHINE_SLICE.varying)
    shape = (len(h), len(v))
    X, Y = grid["mfr"].to_numpy().reshape(shape), grid[y].to_numpy().reshape(shape)
    sx, sy = grid["mfr_model_sd"].to_numpy().reshape(shape), grid[f"{y}_model_sd"].to_numpy().reshape(shape)
    ok = grid["supported"].to_numpy().reshape(shape)
    fig = new_figure(8.6, 6.6)
    ax = fig.subplots()
    set_limits(ax, np.concatenate([(X - sx).ravel(), (X + sx).ravel()]),
               np.concatenate([(Y - sy).ravel(), (Y + sy).ravel()]), pad=0.1, pad_right=0.26, pad_top=0.12)
    cmap = matplotlib.colormaps["viridis"]
    vnorm = mcolors.Normalize(v.min(), v.max())
    for j in range(len(v) - 1):  # bands between neighbouring speed lines
        xs = np.concatenate([X[:, j], X[::-1, j + 1]])
        ys = np.concatenate([Y[:, j], Y[::-1, j + 1]])
        ax.fill(xs, ys, color=cmap(vnorm((v[j] + v[j + 1]) / 2)), alpha=0.3, lw=0, zorder=1)
        for i in range(len(h) - 1):
            if not ok[i:i + 2, j:j + 2].all():
                quad = [(X[i, j], Y[i, j]), (X[i + 1, j], Y[i + 1, j]), (X[i + 1, j + 1], Y[i + 1, j + 1]),
                        (X[i, j + 1], Y[i, j + 1])]
                ax.add_patch(Polygon(quad, closed=True, zorder=2, **HATCH))
    v_lab, h_lab = which_labelled(len(v), max_labels), which_labelled(len(h), max_labels)
    for j in range(len(v)):
        ax.plot(X[:, j], Y[:, j], color=cmap(vnorm(v[j])), lw=2.2 if j in v_lab else 1.0, zorder=3)
    for i in range(len(h)):
        ax.plot(X[i], Y[i], color="0.15", lw=1.3 if i in h_lab else 0.6, ls="--", zorder=4)
    for x0, y0, a, b in zip(X.ravel(), Y.ravel(), sx.ravel(), sy.ravel()):
        ax.add_patch(Ellipse((x0, y0), 2 * a, 2 * b, fc="0.5", ec="0.3", alpha=0.18, lw=0.5, zorder=2.5))
    ax.scatter(X[ok], Y[ok], s=14, color="black", zorder=5)
    ax.scatter(X[~ok], Y[~ok], s=22, facecolor="white", edgecolor="black", zorder=5)
    cb = fig.colorbar(matplotlib.cm.ScalarMappable(norm=vnorm, cmap=cmap), ax=ax, pad=0.02)
    cb.set_label(BY_NAME["v_mm_s"].label + "  (bands between neighbouring v lines)")
    cb.set_ticks(v if len(v) <= 12 else np.linspace(v.min(), v.max(), 6))
    # one DEM run's noise: a cross (and its note to the right of it) in the corner the map leaves emptiest
    nx, ny = float(np.median(grid["mfr_noise_sd"])), float(np.median(grid[f"{y}_noise_sd"]))
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    fx, fy = emptiest_corner(ax, X.ravel(), Y.ravel())
    cx, cy = x0 + fx * (x1 - x0) + nx, y0 + fy * (y1 - y0) + (ny if fy < 0.5 else -ny)
    ax.errorbar([cx], [cy], xerr=[nx], yerr=[ny], color="darkred", capsize=3, lw=1.2, zorder=6)
    ax.annotate(f"± one DEM run's noise SD\n(MFR {nx:.3f}, {short(y)} {ny:.3f})", (cx + nx, cy),
                xytext=(6, 0), textcoords="offset points", va="center", fontsize=7.5, color="darkred")
    placed = []
    for j in range(len(v)):
        if j in v_lab:
            end_label(ax, X[:, j], Y[:, j], BY_NAME["v_mm_s"].text(v[j]), edge=mcolors.to_hex(cmap(vnorm(v[j]))),
                      placed=placed)
    for i in range(len(h)):
        if i in h_lab:
            end_label(ax, X[i], Y[i], BY_NAME["h_um"].text(h[i]), colour="0.1", edge="0.3", placed=placed)
    handles = [Line2D([], [], color=cmap(0.6), lw=2.2, label="constant blade speed v (solid)"),
               Line2D([], [], color="0.15", lw=1.3, ls="--", label="constant layer thickness h (dashed)"),
               Line2D([], [], marker="o", ls="", color="0.5", alpha=0.4, ms=9, label="± one model SD (ellipse)"),
               Line2D([], [], marker="o", ls="", mfc="white", mec="black", ms=5, label="setting beyond the data")]
    # "best" avoids the lines, the bands and the placed labels (matplotlib counts Text artists too)
    ax.legend(handles=handles, loc="best", fontsize=7.5, framealpha=0.9)
    ax.set_xlabel(axis_label("mfr"))
    ax.set_ylabel(axis_label(y))
    if definition(y):
        fig.text(0.02, -0.045, definition(y), fontsize=7, va="top", ha="left", color="0.25")
    if y_note:  # how far y is from MFR in disguise, across the sample
        ax.text(0.01, 0.01, y_note, transform=ax.transAxes, fontsize=7, va="bottom", ha="left", color="0.25")
    ax.grid(alpha=0.3)
    beyond = "" if ok.any() else "BEYOND THE DATA: "
    title = ax.set_title(f"{beyond}Machine map at {slices.text(MACHINE_SLICE.fixed_of(grid))}: "
                         f"h {fmt(h.min())}-{fmt(h.max())} um, v {fmt(v.min())}-{fmt(v.max())} mm/s"
                         + with_model_note(model_note), fontsize=10)
    note = support_note(fig, grid["supported"].to_numpy(), support, "settings")
    paths = save_figure(fig, stem, grid, floor)
    return MapResult(paths, grid, {"y": y, "note": note, "title": title.get_text(), "n_unsupported": int((~ok).sum())})
