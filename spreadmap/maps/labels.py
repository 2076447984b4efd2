"""Labels on map lines: at a line's end, pushed clear of the labels already placed."""
from __future__ import annotations

import numpy as np


def end_label(ax, xs, ys, text, colour="black", at: str = "end", fontsize: float = 8,
               distance: float = 6.0, edge: str | None = None,
               placed: list | None = None) -> None:
    """Write ``text`` just beyond one end of the polyline (xs, ys), in the line's direction.

    With ``placed`` (a list shared by the labels of one axes) a label that would overlap one
    already placed is pushed further out along the line (then sideways) until it is free,
    and joined to its line end by a thin leader.  Call after the axes' size and limits are
    final (colour bars added, limits set).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.
    xs, ys : array_like
        The polyline's points, in data units.
    text : str
        The label.
    colour : color, optional
        The text's colour (matplotlib colour).
    at : {"end", "start"}, optional
        Which end of the line to label.
    fontsize : float, optional
        Font size [pt].
    distance : float, optional
        The label's offset from the line end [pt], before any push.
    edge : color or None, optional
        The colour of the label box's edge and of the leader; None: no edge, the leader in
        ``colour``.
    placed : list or None, optional
        The bounding boxes (display units) of the labels placed so far on these axes; this label's
        box is appended. None: no check for overlaps.
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


def spread(values: np.ndarray, gap: float, low: float, high: float) -> np.ndarray:
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


def right_labels(ax, x_end: float, ys, texts, colours, fontsize: float = 8) -> None:
    """Label curves at their right end x_end, labels spread vertically so they never overlap.

    Each label is joined to its curve end by a thin leader.  Call after the y limits are final.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.
    x_end : float
        The curves' right end, in data units.
    ys : array_like
        Each curve's value at ``x_end``, in data units.
    texts : sequence of str
        The labels, one per curve.
    colours : sequence of color
        The labels' colours, one per curve.
    fontsize : float, optional
        Font size [pt]; the labels' spacing grows with it.
    """
    y0, y1 = ax.get_ylim()
    x0, x1 = ax.get_xlim()
    gap = 0.055 * (y1 - y0) * fontsize / 8
    ys = np.asarray(ys, float)
    pos = spread(ys, gap, y0 + 0.5 * gap, y1 - 0.5 * gap)
    xt = x_end + 0.04 * (x1 - x0)
    for y, yt, text, c in zip(ys, pos, texts, colours):
        ax.annotate(text, (x_end, y), xytext=(xt, yt), textcoords="data", ha="left",
                    va="center", fontsize=fontsize, color=c, zorder=6,
                    arrowprops=dict(arrowstyle="-", color=c, lw=0.6, shrinkA=0, shrinkB=1))


def which_labelled(n: int, max_labels: int) -> set[int]:
    """Indices of the lines that get a label: all if few, else every k-th from the first, and the last.

    k is the smallest step that keeps the count within ``max_labels``.

    Parameters
    ----------
    n : int
        How many lines.
    max_labels : int
        How many labels at most (the last line's label may add one).

    Returns
    -------
    set of int
        The indices of the lines to label.
    """
    if n <= max_labels:
        return set(range(n))
    step = int(np.ceil((n - 1) / max(max_labels - 1, 1)))
    return set(range(0, n, step)) | {n - 1}
