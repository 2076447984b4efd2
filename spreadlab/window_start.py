"""Where does the flow under the blade settle? A case's flow along the blade's travel beyond the pile,
read from its raw record's volume-behind series, and its window opened later (issue 50's steady window).

The scene opens the measurement window a fixed `transient_d` beyond the pile and closes it
`window_d` later; the series runs from the blade's start to the window's end. From it, without
another DEM run:

* ``flow_profile``: the flow over bins of travel beyond the pile (in d), over the window's own mean
  flow: a flow still rising when the window opens shows as bins below 1 early in the window;
* ``window_profile``: the same over equal parts of the case's own window (its trend, seen);
* ``later_window``: MFR and the steady flag's statistic (``noise.flow_trend_batch_z``) of a window that
  opens `open_d` beyond the pile and ends where the case's window ended. MFR here is the series'
  (spheres counted by centre over gap x width x travel), close to but not the case's MFR (which
  counts volume exactly from the snapshots): compare windows of one case with each other only.
"""
from __future__ import annotations

import math

import numpy as np

from spreadmap.metrics.noise import flow_trend_batch_z


def _series(raw: dict) -> tuple[np.ndarray, np.ndarray]:
    arr = np.asarray(raw.get("behind_series") or [], float).reshape(-1, 3)
    return arr[:, 1], arr[:, 2]


def pile_end(raw: dict) -> float:
    """The pile's front at the blade's start [m]: where `transient_d` is counted from."""
    return float(raw["geometry"]["pile_length"])


def diameter(raw: dict) -> float:
    """The spheres' diameter the scene was sized by [m] (one size: d; a size distribution: its D50)."""
    return float(raw["params"]["diameter"])


def flow_profile(raw: dict, edges_d) -> np.ndarray:
    """The flow over each bin of travel [edges_d[i], edges_d[i+1]] beyond the pile, in d, over the
    mean flow of the case's window; NaN for a bin the series does not cover."""
    x, vol = _series(raw)
    x_pile, d = pile_end(raw), diameter(raw)
    x0, x1 = raw["window"]["x_start"], raw["window"]["x_end"]
    if len(x) < 2 or x[-1] < x1 or x1 <= x0:
        return np.full(len(edges_d) - 1, math.nan)
    mean = (np.interp(x1, x, vol) - np.interp(x0, x, vol)) / (x1 - x0)
    xs = x_pile + np.asarray(edges_d, float) * d
    v = np.interp(xs, x, vol)
    out = np.diff(v) / np.diff(xs) / mean
    out[(xs[:-1] < x[0]) | (xs[1:] > x[-1])] = math.nan
    return out


def window_profile(raw: dict, parts: int) -> np.ndarray:
    """The flow over each of `parts` equal parts of the case's own window, over the window's mean
    flow (a window long at a thin gap and short at a wide one read on one axis); NaN if the series
    does not cover the window."""
    x, vol = _series(raw)
    x0, x1 = raw["window"]["x_start"], raw["window"]["x_end"]
    if len(x) < 2 or x[0] > x0 or x[-1] < x1 or x1 <= x0:
        return np.full(parts, math.nan)
    xs = np.linspace(x0, x1, parts + 1)
    v = np.interp(xs, x, vol)
    return np.diff(v) / np.diff(xs) / ((v[-1] - v[0]) / (x1 - x0))


def later_window(raw: dict, open_d: float, batches: int = 8) -> dict:
    """MFR (from the series) and the flow-trend z of the window [pile + open_d d, the case's window
    end]; NaN where the window would be shorter than 2 d or the series does not cover it."""
    x, vol = _series(raw)
    x_pile, d = pile_end(raw), diameter(raw)
    x0, x1 = x_pile + open_d * d, raw["window"]["x_end"]
    geom = raw["geometry"]
    if len(x) < 3 or x1 - x0 < 2.0 * d or x[0] > x0 or x[-1] < x1:
        return {"open_d": open_d, "length_d": (x1 - x0) / d, "mfr_series": math.nan, "trend_z": math.nan}
    passed = np.interp(x1, x, vol) - np.interp(x0, x, vol)
    z, _ = flow_trend_batch_z(raw["behind_series"], x0, x1, batches)
    return {"open_d": open_d, "length_d": (x1 - x0) / d,
            "mfr_series": passed / (geom["gap"] * geom["width"] * (x1 - x0)), "trend_z": z}
