"""The sizes of a case's spheres: the feed's volume quantiles (D10, D50, D90, as a powder
certificate gives them), the gap over D90, and the segregation of the spread layer (the layer's D50
over the feed's, with its SD).

The feed is the pile as the blade starts (every powder sphere of the ``blade_start`` snapshot); the
layer is the spheres whose centres lie in the PD box at the window's end (the span measured behind
the blade, below the gap). Quantiles are by volume: the diameter below which a fraction q of the
spheres' volume lies (linear interpolation of the cumulative volume between sorted diameters).
The layer ratio's SD is a bootstrap over the layer's spheres (fixed seed: the same record gives the
same SD). Spheres of one size give D10 = D50 = D90 = d and a ratio of 1 with SD 0.
"""
from __future__ import annotations

import math

import numpy as np

from .flow import powder

BOOTSTRAP = 200  # resamples of the layer's spheres for the ratio's SD
BOOTSTRAP_SEED = 12345


def volume_quantile(diameters, q: float) -> float:
    """The diameter below which a volume fraction q of the spheres lies (NaN without spheres)."""
    d = np.sort(np.asarray(diameters, float))
    if d.size == 0:
        return math.nan
    if d[0] == d[-1]:
        return float(d[0])
    volume = d ** 3
    cumulative = (np.cumsum(volume) - 0.5 * volume) / volume.sum()  # each sphere at its volume's midpoint
    return float(np.interp(q, cumulative, d))


def _layer_diameters(snapshot: dict, x0: float, x1: float, gap: float) -> np.ndarray:
    positions, radii = powder(snapshot)
    inside = (positions[:, 0] >= x0) & (positions[:, 0] <= x1) & (positions[:, 2] < gap)
    return 2.0 * radii[inside]


def size_measures(blade_start: dict, window_end: dict, x0: float, x1: float, gap: float) -> dict:
    """The feed's D10 / D50 / D90 [um], gap / D90, and the layer's D50 over the feed's with its SD.

    Parameters
    ----------
    blade_start, window_end : dict
        Snapshots of the raw record (positions, radii [m]).
    x0, x1 : float
        The PD box's span along the travel [m] (``flow.measured_span``).
    gap : float
        The gap h [m].

    Returns
    -------
    dict
        ``feed_d10_um``, ``feed_d50_um``, ``feed_d90_um``, ``h_over_d90``, ``layer_d50_ratio`` and
        ``layer_d50_ratio_sd`` (NaN without spheres in the layer).
    """
    _, radii = powder(blade_start)
    feed = 2.0 * radii
    d10, d50, d90 = (volume_quantile(feed, q) for q in (0.1, 0.5, 0.9))
    layer = _layer_diameters(window_end, x0, x1, gap)
    ratio = volume_quantile(layer, 0.5) / d50 if layer.size else math.nan
    if layer.size == 0:
        sd = math.nan
    elif layer.min() == layer.max():
        sd = 0.0
    else:
        rng = np.random.default_rng(BOOTSTRAP_SEED)
        draws = [volume_quantile(rng.choice(layer, layer.size), 0.5) / d50 for _ in range(BOOTSTRAP)]
        sd = float(np.std(draws, ddof=1))
    return {"feed_d10_um": d10 * 1e6, "feed_d50_um": d50 * 1e6, "feed_d90_um": d90 * 1e6,
            "h_over_d90": gap / d90, "layer_d50_ratio": ratio, "layer_d50_ratio_sd": sd}
