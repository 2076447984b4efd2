"""Pictures of one spreading case: the powder bed, the blade and the deposit at a few moments.

:func:`plot_case_views` draws one figure per case from its raw result (``raw.json`` of
``yade_scripts/spreading_case.py``) and saves it through :func:`spreadmap.figures.save_figure`
as ``<stem>.png``, ``<stem>.pdf`` and the sphere table as ``<stem>.csv``.

What the figure shows
---------------------
One row per moment (blade start, window middle, window end; when a snapshot is missing, the
other recorded moments stand in, chronologically).  Each row holds

* a side view (x-z, looking along +y, far spheres drawn first) and, below it on the same x axis,
* a top view (x-y, looking down, higher spheres drawn last),

with every sphere drawn to scale as a circle of its radius in data units (equal aspect, so a
sphere is a circle on the page), coloured by its speed |v| (mm/s; the blade speed marked on the
colour bar) or by its height z (um; the gap h marked).  The blade is a grey rectangle (side view:
x from its rear to its front face, z from the gap up; top view: translucent over the full width,
so the spheres passing under it stay visible); the gap is dimensioned by an arrow from the floor
to the blade's lower face labelled "h = .. um"; a dashed line continues the blade's lower face
behind it (the nominal top of the layer).  The floor (z = 0, hatched below, only where the floor
exists) and the frictionless side walls (y = 0, y = width, hatched outside) are drawn.  On the
window-end row the PD sampling box (blade rear face at window start to window end, z in [0, h],
full width) is outlined, dashed (red on the speed colours, cyan on the height colours).

Axes are in micrometres.  The x range is the region of interest, shared by all rows: the blade
positions, the deposit behind the blade back to where the blade started, and the contiguous
bed (pile) that touches the blade -- spheres that rolled more than a few diameters away from the
bed are left out and counted in the row's header ("outside the view: n behind, m ahead").
The title gives the case id, f, d, h (and h/d), v, the sphere count and the status; each row's
header the moment, its time, the time since the blade started and the blade travel.

The CSV holds every sphere of every moment drawn (also those outside the view): ``moment``,
``x_um``, ``y_um``, ``z_um``, ``r_um``, ``speed_mm_s``.
"""
from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib import colors as mcolors  # noqa: E402
from matplotlib import patheffects  # noqa: E402
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle, Patch, Rectangle  # noqa: E402

from spreadmap.design import h_over_d  # noqa: E402
from spreadmap.figures import save_figure  # noqa: E402

__all__ = ["plot_case_views", "build_case_figure", "choose_moments", "sphere_table", "view_window",
           "MOMENT_ORDER", "PREFERRED_MOMENTS", "TABLE_COLUMNS"]

UM = 1e6  # m -> um
MM_S = 1e3  # m/s -> mm/s

MOMENT_ORDER = ("settled", "blade_start", "window_start", "window_middle", "window_end")
PREFERRED_MOMENTS = ("blade_start", "window_middle", "window_end")
MOMENT_LABELS = {
    "settled": "poured bed (settled)",
    "blade_start": "blade starts moving",
    "window_start": "measurement window opens",
    "window_middle": "middle of the measurement window",
    "window_end": "measurement window closes",
}
TABLE_COLUMNS = ("moment", "x_um", "y_um", "z_um", "r_um", "speed_mm_s")

BLADE_FACE = "0.62"
BLADE_EDGE = "0.25"
PD_BOX_COLOURS = {"speed": "tab:red", "height": "tab:cyan"}  # away from each colour map
CLUSTER_GAP_D = 4.0  # spheres further than this many diameters from the bed are stragglers


# ---------------------------------------------------------------------------------------------
# data
# ---------------------------------------------------------------------------------------------
def _order_key(snapshots: dict, name: str) -> tuple:
    t = snapshots[name].get("time")
    t = float(t) if isinstance(t, (int, float)) and math.isfinite(t) else math.inf
    rank = MOMENT_ORDER.index(name) if name in MOMENT_ORDER else len(MOMENT_ORDER)
    return (rank, t, name)


def choose_moments(snapshots: dict, n: int = 3) -> list[str]:
    """The moments to draw, chronologically.

    Blade start, window middle and window end where they exist, filled up to ``n`` with the other
    recorded moments (window start, settled, ...).

    Parameters
    ----------
    snapshots : dict
        A raw result's ``snapshots``: moment name -> snapshot (its ``time`` [s] orders moments of
        no known name); None or empty: none.
    n : int, optional
        How many moments at most.

    Returns
    -------
    list of str
        The moments' names in chronological order (``MOMENT_ORDER``, then by time and name).
    """
    snapshots = snapshots or {}
    present = sorted(snapshots, key=lambda m: _order_key(snapshots, m))
    chosen = [m for m in PREFERRED_MOMENTS if m in snapshots][:n]
    for m in present:
        if len(chosen) >= n:
            break
        if m not in chosen:
            chosen.append(m)
    return sorted(chosen, key=lambda m: _order_key(snapshots, m))


def _arrays(snapshot: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (n, 3) and radii (n,) in um, speeds (n,) in mm/s (NaN if not recorded)."""
    pos = np.asarray(snapshot.get("positions", []), dtype=float).reshape(-1, 3) * UM
    rad = np.asarray(snapshot.get("radii", []), dtype=float).reshape(-1) * UM
    vel = snapshot.get("velocities")
    if vel is None or len(vel) != len(pos):
        speed = np.full(len(pos), np.nan)
    else:
        speed = np.linalg.norm(np.asarray(vel, dtype=float).reshape(-1, 3), axis=1) * MM_S
    if rad.shape != (len(pos),):
        raise ValueError(f"snapshot has {len(pos)} positions but {rad.size} radii")
    return pos, rad, speed


def sphere_table(raw: dict, moments=None) -> pd.DataFrame:
    """Every sphere of each moment, in um and mm/s: columns ``moment, x_um, y_um, z_um, r_um, speed_mm_s``.

    Parameters
    ----------
    raw : dict
        The case's raw result (its ``snapshots``: ``positions`` [m], ``radii`` [m], optionally
        ``velocities`` [m/s]).
    moments : iterable of str or None, optional
        The moments; None: those :func:`choose_moments` picks.

    Returns
    -------
    pandas.DataFrame
        One row per sphere and moment: ``moment``, the centre ``x_um``, ``y_um``, ``z_um`` [um], the
        radius ``r_um`` [um] and ``speed_mm_s`` (|v| [mm/s]; NaN where the velocities are not
        recorded); empty, with those columns, without moments.

    Raises
    ------
    ValueError
        If a snapshot's radii do not match its positions.
    """
    snapshots = raw.get("snapshots") or {}
    moments = choose_moments(snapshots) if moments is None else list(moments)
    frames = []
    for m in moments:
        pos, rad, speed = _arrays(snapshots[m])
        frames.append(pd.DataFrame({"moment": m, "x_um": pos[:, 0], "y_um": pos[:, 1], "z_um": pos[:, 2],
                                    "r_um": rad, "speed_mm_s": speed}))
    if not frames:
        return pd.DataFrame({c: pd.Series(dtype=object if c == "moment" else float) for c in TABLE_COLUMNS})
    return pd.concat(frames, ignore_index=True)[list(TABLE_COLUMNS)]


def _case_values(raw: dict) -> dict:
    """Case id, the design point (f, d_um, h_um, v_mm_s) and the geometry in um."""
    p = raw.get("params") or {}
    g = raw.get("geometry") or {}
    point = dict(p.get("point") or {})
    fallback = {"f": p.get("friction"), "d_um": _scaled(p.get("diameter"), UM),
                "h_um": _scaled(p.get("gap", g.get("gap")), UM), "v_mm_s": _scaled(p.get("blade_speed"), MM_S)}
    for k, v in fallback.items():
        if point.get(k) is None:
            point[k] = v
    d_um = _scaled(p.get("diameter"), UM) or point.get("d_um")
    return {
        "case_id": str(p.get("case_id", "?")),
        "point": point,
        "d_um": d_um,
        "gap_um": _scaled(g.get("gap", p.get("gap")), UM) or point.get("h_um"),
        "width_um": _scaled(g.get("width", p.get("width")), UM),
        "blade_um": _scaled(g.get("blade_thickness", p.get("blade_thickness")), UM),
        "blade_top_um": _scaled(g.get("blade_top"), UM),
        "floor_um": [_scaled(x, UM) for x in g["floor_x"]] if g.get("floor_x") else None,
        "blade_speed_mm_s": _scaled(p.get("blade_speed"), MM_S) or point.get("v_mm_s"),
    }


def _scaled(x, factor):
    return None if x is None else float(x) * factor


def _cluster_extent(x: np.ndarray, lo: float, hi: float, max_gap: float) -> tuple[float, float]:
    """Grow [lo, hi] over the sorted sphere centres x while the next one is within max_gap."""
    xs = np.sort(x[np.isfinite(x)])
    right = xs[xs > hi]
    for v in right:
        if v - hi > max_gap:
            break
        hi = v
    left = xs[xs < lo][::-1]
    for v in left:
        if lo - v > max_gap:
            break
        lo = v
    return lo, hi


def view_window(raw: dict, moments=None) -> dict:
    """The region drawn (um): ``x`` (lo, hi) shared by all rows, ``z`` and ``y`` ranges.

    x covers every blade position drawn, the deposit back to where the blade started, and the
    bed that is contiguous with the blade (centres within 4 d of one another); far stragglers
    are left out.  z runs from just below the floor to above the highest sphere in view (at most
    the blade top); y spans the side walls.

    Parameters
    ----------
    raw : dict
        The case's raw result (its ``snapshots``, ``params`` and ``geometry``, SI units).
    moments : iterable of str or None, optional
        The moments drawn; None: those :func:`choose_moments` picks.

    Returns
    -------
    dict
        ``x``, ``z`` and ``y``: (low, high) [um]; ``width``: the distance between the side walls
        [um] (from the raw result, else from the spheres); ``d``: the particle diameter [um] (30
        where the raw result does not say).

    Raises
    ------
    ValueError
        If a snapshot's radii do not match its positions.
    """
    snapshots = raw.get("snapshots") or {}
    moments = choose_moments(snapshots) if moments is None else list(moments)
    cv = _case_values(raw)
    d = cv["d_um"] or 30.0
    tb = cv["blade_um"] or 0.0
    lo, hi = math.inf, -math.inf
    for m in moments:
        pos, rad, _ = _arrays(snapshots[m])
        rear = snapshots[m].get("blade_rear_x")
        if rear is not None:
            b_lo, b_hi = rear * UM, rear * UM + tb
        elif len(pos):
            b_lo = b_hi = float(np.nanmedian(pos[:, 0]))
        else:
            continue
        if "blade_start" in snapshots and snapshots["blade_start"].get("blade_rear_x") is not None:
            b_lo = min(b_lo, snapshots["blade_start"]["blade_rear_x"] * UM)  # deposit region
        c_lo, c_hi = _cluster_extent(pos[:, 0], b_lo, b_hi, CLUSTER_GAP_D * d) if len(pos) else (b_lo, b_hi)
        r_max = float(np.nanmax(rad)) if len(rad) else 0.0
        lo, hi = min(lo, c_lo - r_max), max(hi, c_hi + r_max)
    if not math.isfinite(lo):
        lo, hi = 0.0, 10.0 * d
    lo, hi = lo - 1.5 * d, hi + 1.5 * d
    if cv["floor_um"]:
        lo, hi = max(lo, cv["floor_um"][0] - d), min(hi, cv["floor_um"][1] + d)
    gap = cv["gap_um"] or 0.0
    top = gap
    for m in moments:
        pos, rad, _ = _arrays(snapshots[m])
        inside = (pos[:, 0] >= lo) & (pos[:, 0] <= hi) & np.isfinite(pos[:, 2])
        if inside.any():
            top = max(top, float(np.max(pos[inside, 2] + rad[inside])))
    z_hi = top + 1.2 * d
    if cv["blade_top_um"]:
        z_hi = min(z_hi, max(cv["blade_top_um"], gap + 2.0 * d))
    z_hi = max(z_hi, gap + 1.5 * d)
    width = cv["width_um"]
    if width is None:
        ys = [_arrays(snapshots[m])[0][:, 1] for m in moments]
        ys = np.concatenate(ys) if ys else np.zeros(0)
        width = float(np.nanmax(ys) + d / 2) if ys.size else 3.0 * d
    return {"x": (lo, hi), "z": (-0.55 * d, z_hi), "y": (-0.45 * d, width + 0.45 * d), "width": width, "d": d}


# ---------------------------------------------------------------------------------------------
# drawing
# ---------------------------------------------------------------------------------------------
def _spheres(ax, cx, cy, r, values, order, cmap, norm, lw, gid):
    circles = [Circle((cx[i], cy[i]), r[i]) for i in order]
    pc = PatchCollection(circles, cmap=cmap, norm=norm, edgecolors=(0.1, 0.1, 0.1, 0.75), linewidths=lw, zorder=2)
    pc.set_array(np.asarray(values, float)[order])
    pc.set_gid(gid)
    ax.add_collection(pc)
    return pc


def _hatch(ax, x0, x1, y0, y1):
    if x1 > x0 and y1 > y0:
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="0.93", edgecolor="0.55", hatch="////",
                               linewidth=0, zorder=1))


def _outside_note(pos, lo, hi, zhi):
    x, z = pos[:, 0], pos[:, 2]
    behind = int(np.sum(x < lo))
    ahead = int(np.sum(x > hi))
    above = int(np.sum((x >= lo) & (x <= hi) & (z > zhi)))
    parts = []
    if behind:
        parts.append(f"{behind} behind (x < {lo:.0f} µm)")
    if ahead:
        parts.append(f"{ahead} ahead (x > {hi:.0f} µm)")
    if above:
        parts.append(f"{above} above the view")
    return ("outside the view: " + ", ".join(parts)) if parts else "all in view"


def _gap_label(ax, text, xr, tb, gap, x0, x1, z1, scale, fontsize=8.0):
    """Label the gap: left of the blade, above the nominal layer top (free space behind the blade);
    if that does not fit in the view, inside the blade (written upwards), else right of it."""
    bbox = dict(boxstyle="round,pad=0.2", fc="white", ec="0.5", lw=0.6, alpha=0.9)
    width_pt = 0.62 * fontsize * len(text) + 8.0  # generous estimate of the boxed text's length
    pt_per_um = scale * 72.0
    if (xr - x0) * pt_per_um >= width_pt + 6.0:
        ax.annotate(text, xy=(xr, gap), xytext=(-4, 5), textcoords="offset points", ha="right", va="bottom",
                    fontsize=fontsize, zorder=7, bbox=bbox)
    elif (z1 - gap) * pt_per_um >= width_pt + 6.0 and tb * pt_per_um >= fontsize + 4.0:
        ax.annotate(text, xy=(xr + 0.5 * tb, gap), xytext=(0, 5), textcoords="offset points", ha="center",
                    va="bottom", rotation=90, fontsize=fontsize, zorder=7, bbox=bbox)
    else:
        ax.annotate(text, xy=(min(xr + tb, x1), gap), xytext=(4, 5), textcoords="offset points", ha="left",
                    va="bottom", fontsize=fontsize, zorder=7, bbox=bbox)


def _fmt_num(x, digits=3):
    if x is None or not math.isfinite(x):
        return "?"
    return f"{x:.{digits}g}"


def build_case_figure(raw: dict, colour_by: str = "speed"):
    """The figure (not saved) and the sphere table behind it. See the module docstring.

    Parameters
    ----------
    raw : dict
        The case's raw result (raw.json of yade_scripts/spreading_case.py, SI units).
    colour_by : {"speed", "height"}, optional
        Colour the spheres by their speed |v| [mm/s] or their height z [um].

    Returns
    -------
    fig : matplotlib.figure.Figure
        The figure; its ``spreadmap_axes`` holds the ``side`` and ``top`` axes, the ``colorbar``
        axes and the ``moments`` drawn.
    table : pandas.DataFrame
        The spheres of the moments drawn (``sphere_table``).

    Raises
    ------
    ValueError
        If ``colour_by`` is neither "speed" nor "height", or a snapshot's radii do not match its
        positions.
    """
    if colour_by not in ("speed", "height"):
        raise ValueError(f"colour_by must be 'speed' or 'height', not {colour_by!r}")
    snapshots = raw.get("snapshots") or {}
    moments = choose_moments(snapshots)
    table = sphere_table(raw, moments)
    cv = _case_values(raw)
    pt = cv["point"]
    substrate = raw.get("substrate") or {}
    sub_pos = np.asarray(substrate.get("positions") or np.zeros((0, 3)), float).reshape(-1, 3) * UM
    sub_rad = np.asarray(substrate.get("radii") or [], float) * UM
    title = (f"Powder spreading, case {cv['case_id']}\n"
             f"f = {_fmt_num(pt.get('f'))},  d = {_fmt_num(pt.get('d_um'))} µm,  h = {_fmt_num(pt.get('h_um'))} µm"
             + (f" (h/d = {float(h_over_d(pt)):.2f})" if pt.get("h_um") and pt.get("d_um") else "")
             + f",  v = {_fmt_num(pt.get('v_mm_s'))} mm/s")
    n_sph = raw.get("n_particles") or (len(snapshots[moments[0]].get("positions", [])) if moments else 0)
    status = raw.get("status")
    title += f"   ·   {n_sph} spheres" + (f"   ·   status {status}" if status else "")

    if not moments:
        fig = plt.figure(figsize=(8, 2.2))
        fig.suptitle(title, fontsize=10)
        reason = raw.get("reason") or ""
        fig.text(0.5, 0.4, "no snapshots recorded" + (f"\n{reason}" if reason else ""), ha="center", va="center",
                 fontsize=10, color="0.3")
        return fig, table

    win = view_window(raw, moments)
    (x0, x1), (z0, z1), (y0, y1) = win["x"], win["z"], win["y"]
    d, width = win["d"], win["width"]
    gap = cv["gap_um"]
    tb = cv["blade_um"] or 0.0

    # ---- colours ----
    if colour_by == "speed":
        vals = table["speed_mm_s"].to_numpy(float)
        finite = vals[np.isfinite(vals)]
        v_blade = cv["blade_speed_mm_s"] or (float(np.max(finite)) if finite.size else 1.0)
        top = max(1.5 * v_blade, float(np.percentile(finite, 99)) if finite.size else 0.0)
        vmax = min(top, 4.0 * v_blade)
        extend = "max" if finite.size and finite.max() > vmax else "neither"
        cmap = plt.get_cmap("viridis").copy()
        clabel = "sphere speed |v|  [mm/s]"
        mark, mark_label = v_blade, "blade v ="
    else:
        vals = table["z_um"].to_numpy(float)
        in_view = (table["x_um"].between(x0, x1) & (table["z_um"] <= z1)).to_numpy()
        vmax = max(float(np.nanmax(vals[in_view])) if in_view.any() else 0.0, gap or 0.0, d)
        extend = "max" if np.nanmax(vals) > vmax else "neither"
        cmap = plt.get_cmap("plasma").copy()
        clabel = "sphere centre height z  [µm]"
        mark, mark_label = gap, "h ="
    cmap = cmap.with_extremes(bad="0.8")
    pd_colour = PD_BOX_COLOURS[colour_by]
    norm = mcolors.Normalize(vmin=0.0, vmax=vmax if vmax > 0 else 1.0)

    # ---- layout in inches: equal aspect by construction ----
    left, right_space, plot_w = 0.8, 1.35, 10.6
    head_h, side_gap, tick_h, row_gap, title_h, legend_h = 0.42, 0.07, 0.3, 0.14, 0.85, 0.5
    rows = len(moments)
    data_h = (z1 - z0) + (y1 - y0)
    fixed_h = title_h + legend_h + rows * (head_h + side_gap + tick_h + row_gap) + 0.25
    scale = plot_w / (x1 - x0)  # inches per um
    max_h = 15.0
    if fixed_h + rows * data_h * scale > max_h:
        scale = (max_h - fixed_h) / (rows * data_h)
        plot_w = scale * (x1 - x0)
    fig_w = left + max(plot_w, 6.0) + right_space
    fig_h = fixed_h + rows * data_h * scale
    fig = plt.figure(figsize=(fig_w, fig_h))

    def axes_at(x_in, y_top_in, w_in, h_in):
        return fig.add_axes([x_in / fig_w, (fig_h - y_top_in - h_in) / fig_h, w_in / fig_w, h_in / fig_h])

    sphere_pts = 2.0 * np.nanmedian(table["r_um"]) * scale * 72.0 if len(table) else 10.0
    lw = float(np.clip(0.06 * sphere_pts, 0.15, 0.6))
    fig.text(left / fig_w, 1 - 0.12 / fig_h, title, ha="left", va="top", fontsize=11)
    colour_note = ("colour: speed |v|" if colour_by == "speed" else "colour: height z")
    fig.text(left / fig_w, 1 - 0.62 / fig_h,
             f"Side views (x–z, seen along +y) above top views (x–y, seen from above) at {rows} moment"
             f"{'s' if rows > 1 else ''}; spheres to scale; {colour_note}.", ha="left", va="top", fontsize=8.5,
             color="0.25")

    t_start = snapshots.get("blade_start", {}).get("time")
    rear_start = snapshots.get("blade_start", {}).get("blade_rear_x")
    win_start = (snapshots.get("window_start", {}).get("blade_rear_x")
                 or (raw.get("window") or {}).get("x_start"))
    win_end = (snapshots.get("window_end", {}).get("blade_rear_x")
               or (raw.get("window") or {}).get("x_end"))
    y_cursor = title_h
    side_axes, top_axes = [], []
    blade_drawn = False
    halo = [patheffects.withStroke(linewidth=2.2, foreground="white")]
    for k, m in enumerate(moments):
        snap = snapshots[m]
        pos, rad, speed = _arrays(snap)
        values = speed if colour_by == "speed" else pos[:, 2]
        t = snap.get("time")
        rear = snap.get("blade_rear_x")
        head = f"{MOMENT_LABELS.get(m, m.replace('_', ' '))}"
        if isinstance(t, (int, float)):
            head += f"   t = {t * 1e3:.2f} ms"
            if isinstance(t_start, (int, float)) and m != "blade_start" and t >= t_start:
                head += f"  ({(t - t_start) * 1e3:.2f} ms after the blade started)"
        if rear is not None:
            sub = f"blade rear face at x = {rear * UM:.0f} µm"
            if rear_start is not None and m != "blade_start":
                sub += f", travel {(rear - rear_start) * UM:.0f} µm"
        else:
            sub = "no blade"
        sub += f"   ·   {len(pos)} spheres, {_outside_note(pos, x0, x1, z1)}"
        fig.text(left / fig_w, 1 - (y_cursor + 0.2) / fig_h, head, ha="left", va="bottom",
                 fontsize=9.5, fontweight="bold")
        fig.text(left / fig_w, 1 - (y_cursor + head_h - 0.05) / fig_h, sub, ha="left", va="bottom",
                 fontsize=8.5, color="0.25")
        y_cursor += head_h
        hs, ht = (z1 - z0) * scale, (y1 - y0) * scale
        ax_s = axes_at(left, y_cursor, plot_w, hs)
        y_cursor += hs + side_gap
        ax_t = axes_at(left, y_cursor, plot_w, ht)
        y_cursor += ht + tick_h + row_gap
        for ax, (lo_, hi_) in ((ax_s, (z0, z1)), (ax_t, (y0, y1))):
            ax.set_xlim(x0, x1)
            ax.set_ylim(lo_, hi_)
            ax.set_aspect("equal", adjustable="box")
            ax.tick_params(labelsize=8)
        ax_s.tick_params(labelbottom=False)
        ax_s.set_ylabel("z [µm]", fontsize=8.5)
        ax_t.set_ylabel("y [µm]", fontsize=8.5)
        if k == rows - 1:
            ax_t.set_xlabel("x [µm]   (blade travels in +x)", fontsize=9)

        # floor (where it exists) and side walls
        f_lo, f_hi = cv["floor_um"] if cv["floor_um"] else (x0, x1)
        _hatch(ax_s, max(x0, f_lo), min(x1, f_hi), z0, 0.0)
        if len(sub_pos):  # a rough substrate: its fixed spheres in grey, their tops at z <= 0
            seen = (sub_pos[:, 0] > x0 - d) & (sub_pos[:, 0] < x1 + d)
            ax_s.add_collection(PatchCollection([Circle((x, z), r) for x, z, r in
                                                 zip(sub_pos[seen, 0], sub_pos[seen, 2], sub_rad[seen])],
                                                facecolor="0.78", edgecolor="0.55", linewidths=0.4, zorder=1.5,
                                                gid=f"substrate:{m}:side"))
        else:
            ax_s.plot([max(x0, f_lo), min(x1, f_hi)], [0, 0], color="black", lw=1.2, zorder=3)
        _hatch(ax_t, x0, x1, y0, 0.0)
        _hatch(ax_t, x0, x1, width, y1)
        ax_t.axhline(0.0, color="black", lw=1.0, zorder=3)
        ax_t.axhline(width, color="black", lw=1.0, zorder=3)

        # spheres: far (large y) first in the side view, low first in the top view
        ok = np.all(np.isfinite(pos), axis=1) & np.isfinite(rad)
        idx = np.flatnonzero(ok)
        _spheres(ax_s, pos[:, 0], pos[:, 2], rad, values, idx[np.argsort(-pos[idx, 1], kind="stable")],
                 cmap, norm, lw, f"spheres:{m}:side")
        _spheres(ax_t, pos[:, 0], pos[:, 1], rad, values, idx[np.argsort(pos[idx, 2], kind="stable")],
                 cmap, norm, lw, f"spheres:{m}:top")

        if rear is not None and gap is not None:
            xr = rear * UM
            blade_drawn = True
            b_top = cv["blade_top_um"] if cv["blade_top_um"] else z1
            ax_s.add_patch(Rectangle((xr, gap), tb, max(b_top, z1) - gap, facecolor=BLADE_FACE, edgecolor=BLADE_EDGE,
                                     lw=1.0, zorder=4, gid=f"blade:{m}:side"))
            ax_t.add_patch(Rectangle((xr, 0.0), tb, width, facecolor=BLADE_FACE, edgecolor=BLADE_EDGE, lw=1.0,
                                     alpha=0.55, zorder=4, gid=f"blade:{m}:top"))
            # nominal layer top behind the blade, and the gap dimension under the blade
            ax_s.plot([x0, xr], [gap, gap], color="0.35", lw=0.8, ls=(0, (4, 3)), zorder=3)
            xa = xr + 0.5 * tb
            ax_s.annotate("", xy=(xa, 0.0), xytext=(xa, gap), zorder=6,
                          arrowprops=dict(arrowstyle="<|-|>", color="black", lw=1.0, shrinkA=0, shrinkB=0,
                                          mutation_scale=7, path_effects=halo))
            _gap_label(ax_s, f"h = {gap:.0f} µm", xr, tb, gap, x0, x1, z1, scale)
        if m == "window_end" and win_start is not None and win_end is not None and gap is not None:
            xs0, xs1 = win_start * UM, win_end * UM
            ax_s.add_patch(Rectangle((xs0, 0.0), xs1 - xs0, gap, fill=False, edgecolor=pd_colour, lw=1.2,
                                     ls=(0, (3, 2)), zorder=5, gid="pd_box:side"))
            ax_t.add_patch(Rectangle((xs0, 0.0), xs1 - xs0, width, fill=False, edgecolor=pd_colour, lw=1.2,
                                     ls=(0, (3, 2)), zorder=5, gid="pd_box:top"))
        side_axes.append(ax_s)
        top_axes.append(ax_t)

    # colour bar over the height of all rows, with the blade speed (or the gap) marked
    top_in = title_h + head_h
    bottom_in = y_cursor - tick_h - row_gap
    cax = axes_at(left + plot_w + 0.22, top_in, 0.16, bottom_in - top_in)
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    cb = fig.colorbar(sm, cax=cax, extend=extend)
    cb.set_label(clabel, fontsize=9)
    cb.ax.tick_params(labelsize=8)
    if mark is not None and 0 < mark <= norm.vmax:
        # the blade speed (or the gap) as a labelled tick of its own, auto ticks too close dropped
        ticks = [v for v in cb.get_ticks() if norm.vmin <= v <= norm.vmax and abs(v - mark) > 0.06 * norm.vmax]
        cb.set_ticks(sorted(ticks + [mark]))
        cb.set_ticklabels([f"{mark_label} {mark:.3g}" if v == mark else f"{v:g}" for v in sorted(ticks + [mark])])
        cb.ax.axhline(mark, color="white", lw=1.8)
        cb.ax.axhline(mark, color="black", lw=0.9, ls=(0, (2, 1.5)))
    handles = [Patch(facecolor=BLADE_FACE, edgecolor=BLADE_EDGE, label="blade (gap h above the floor)"),
               Line2D([], [], color="0.35", lw=0.8, ls=(0, (4, 3)), label="z = h behind the blade (nominal layer top)")]
    handles = handles if blade_drawn else []
    handles.append(Patch(facecolor="0.93", edgecolor="0.55", hatch="////",
                         label="floor (z < 0) / side walls (y = 0, width)"))
    if len(sub_pos):
        handles.append(Patch(facecolor="0.78", edgecolor="0.55", label="rough substrate (fixed spheres, tops at z <= 0)"))
    if "window_end" in moments and win_start is not None and win_end is not None:
        handles.append(Line2D([], [], color=pd_colour, lw=1.2, ls=(0, (3, 2)), label="PD sampling box"))
    legend_top = y_cursor - row_gap + 0.22
    fig.legend(handles=handles, loc="upper left", bbox_to_anchor=(left / fig_w, 1 - legend_top / fig_h),
               ncol=len(handles) if plot_w >= 9.0 else 2,
               fontsize=8, frameon=False, handlelength=2.2, columnspacing=1.6)
    fig.spreadmap_axes = {"side": side_axes, "top": top_axes, "colorbar": cax, "moments": moments}
    return fig, table


def plot_case_views(raw: dict, path_stem, colour_by: str = "speed") -> dict[str, Path]:
    """Draw side and top views of the bed at blade start, window middle and window end (or the moments recorded).

    Spheres to scale, coloured by speed (mm/s) or height (um); saves ``<path_stem>.png/.pdf`` and
    the sphere table ``<path_stem>.csv`` (columns ``moment, x_um, y_um, z_um, r_um, speed_mm_s``;
    every sphere of each moment drawn). See the module docstring for what the figure shows.

    Parameters
    ----------
    raw : dict
        The case's raw result (raw.json of yade_scripts/spreading_case.py, SI units).
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.
    colour_by : {"speed", "height"}, optional
        Colour the spheres by their speed |v| [mm/s] or their height z [um].

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``spreadmap.figures.save_figure``).

    Raises
    ------
    ValueError
        If ``colour_by`` is neither "speed" nor "height" (``build_case_figure``).
    """
    fig, table = build_case_figure(raw, colour_by=colour_by)
    return save_figure(fig, path_stem, table)
