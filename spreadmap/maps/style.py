"""What every map shares: the support note, limits, and the result record (the targets' labels:
``spreadmap.targets``)."""
from __future__ import annotations

import textwrap
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

HATCH = dict(hatch="////", facecolor="none", edgecolor="0.55", lw=0.0)


@dataclass
class MapResult:
    """What a map function wrote: the file paths, the table saved as CSV, and extras.

    Parameters
    ----------
    paths : dict
        The files written: ``png``, ``pdf``, ``csv`` -> pathlib.Path (``figures.save_figure``),
        and any other file the map writes beside them.
    data : pandas.DataFrame
        The table saved as the figure's CSV.
    info : dict, optional
        Extras of the map (e.g. its support note); default {}.
    """

    paths: dict
    data: pd.DataFrame
    info: dict = field(default_factory=dict)


def fmt(value: float, digits: int = 4) -> str:
    """A number as the maps write it: ``digits`` significant digits (``g`` format).

    Parameters
    ----------
    value : float
        The number.
    digits : int, optional
        Significant digits.

    Returns
    -------
    str
        The number formatted.
    """
    return f"{value:.{digits}g}"


def with_model_note(note: str | None, width: int = 120) -> str:
    """What a map's title gets after it for ``note`` (``validation_note``): the note on lines of its
    own, each of its lines wrapped at `width` characters; "" without one (the title unchanged).

    Parameters
    ----------
    note : str or None
        The note; None or "": none.
    width : int, optional
        The longest line [characters].

    Returns
    -------
    str
        "\\n" and the wrapped note, or "".
    """
    if not note:
        return ""
    return "".join("\n" + textwrap.fill(line, width, break_long_words=False) for line in note.split("\n"))


def support_rule(support: dict) -> str:
    """The rule that says where a map is beyond the data, in words (for notes and figures).

    Parameters
    ----------
    support : dict
        The config's ``maps.support``: ``max_distance`` (in median case spacings) and
        ``max_sd_ratio`` (model SD over the noise SD of one run).

    Returns
    -------
    str
        "beyond the data = farther than ... case spacings from every usable case, or model SD >
        ... x the noise SD of one run".
    """
    return (f"beyond the data = farther than {fmt(support['max_distance'], 3)} case spacings from every usable case, "
            f"or model SD > {fmt(support['max_sd_ratio'], 3)} x the noise SD of one run")


def support_note(fig, supported: np.ndarray, support: dict, what: str = "grid points") -> str:
    """Write at the bottom of the figure how much of the map lies beyond the data; return it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The map's figure.
    supported : array_like of bool
        Per point of the map, whether the data support it (``grids.evaluate``'s ``supported``).
    support : dict
        The config's ``maps.support`` (``support_rule``).
    what : str, optional
        What the points are, in the note (e.g. "settings").

    Returns
    -------
    str
        The note: all points supported, or how many of them are beyond the data (then written in
        dark red) and the rule.
    """
    n, k = len(supported), int((~np.asarray(supported)).sum())
    if k == 0:
        text = f"all {n} {what} supported by the data ({support_rule(support)})"
        colour = "0.3"
    else:
        text = (f"{k} of {n} {what} drawn BEYOND THE DATA (hatched / open marks): "
                f"{support_rule(support)}")
        colour = "darkred"
    fig.text(0.5, -0.01, text, ha="center", va="top", fontsize=8, color=colour)
    return text


def set_limits(ax, x, y, pad=0.08, pad_right=None, pad_top=None) -> None:
    """Set the axes' limits to the finite data's range, padded by a share of its span.

    Nothing is set when either coordinate has no finite value; a span below 1e-3 counts as 1e-3.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.
    x, y : array_like
        The values the limits must hold (non-finite ones ignored), in data units.
    pad : float, optional
        The padding on each side, as a share of the span.
    pad_right : float or None, optional
        The padding on the right instead; None: ``pad``.
    pad_top : float or None, optional
        The padding at the top instead; None: ``pad``.
    """
    x = np.asarray(x, float)[np.isfinite(x)]
    y = np.asarray(y, float)[np.isfinite(y)]
    if x.size == 0 or y.size == 0:
        return
    dx, dy = max(np.ptp(x), 1e-3), max(np.ptp(y), 1e-3)
    ax.set_xlim(x.min() - pad * dx, x.max() + (pad if pad_right is None else pad_right) * dx)
    ax.set_ylim(y.min() - pad * dy, y.max() + (pad if pad_top is None else pad_top) * dy)


