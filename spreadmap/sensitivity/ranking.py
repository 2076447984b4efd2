"""Ranks that only separate what the draws separate, and the joined ranking table.

Parameter i is ranked above j when i's value exceeds j's in at least ``confidence`` (97.5 %) of
the paired draws (the same draw of the surrogate for both). A parameter's rank is the range
``1 + (number ranked above it)`` to ``d - (number ranked below it)``: "2" when it is resolved,
"2-3" when the draws cannot order it against a neighbour.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..design import NAMES
from .bands import band_widths
from .sobol import sobol_draws


def rank_by_draws(per_draw: np.ndarray, confidence: float = 0.975) -> list[str]:
    """Rank labels ("1", "2-3", ...) of the columns of (draws, d), largest first."""
    v = np.asarray(per_draw, float)
    d = v.shape[1]
    above = np.zeros((d, d), bool)  # above[i, j]: i confidently larger than j
    for i in range(d):
        for j in range(d):
            if i != j:
                above[i, j] = np.mean(v[:, i] > v[:, j]) >= confidence
    labels = []
    for i in range(d):
        best = 1 + int(above[:, i].sum())
        worst = d - int(above[i, :].sum())
        labels.append(str(best) if best == worst else f"{best}-{worst}")
    return labels


def ranking_table(sobol: pd.DataFrame, sobol_per_draw: dict, bands: pd.DataFrame, band_per_draw: dict) -> pd.DataFrame:
    """One row per (target, parameter): band width and its interval, S1, ST and their intervals,
    the noise share, and the ranks by ST and by band width (ranges where not resolved)."""
    parts = []
    for t in dict.fromkeys(sobol["target"]):
        s = sobol[sobol["target"] == t].set_index("parameter").loc[list(NAMES)].reset_index()
        b = bands[bands["target"] == t].set_index("parameter").loc[list(NAMES)].reset_index()
        s["band"], s["band_low"], s["band_high"] = b["band"], b["band_low"], b["band_high"]
        s["rank_ST"] = rank_by_draws(sobol_per_draw[t]["ST"])
        s["rank_band"] = rank_by_draws(band_per_draw[t])
        parts.append(s.sort_values("ST", ascending=False))
    cols = ["target", "parameter", "band", "band_low", "band_high", "rank_band", "S1", "S1_low", "S1_high",
            "ST", "ST_low", "ST_high", "rank_ST", "noise_share", "noise_share_low", "noise_share_high", "n", "draws"]
    return pd.concat(parts, ignore_index=True)[cols]


def sensitivity(source, targets, n: int = 256, draws: int = 64, ranges=None, seed: int = 0,
                n_sweep: int = 21) -> pd.DataFrame:
    """Band widths and Sobol indices over the same number of draws, joined by ``ranking_table``.

    Parameters
    ----------
    source : draw source
        Anything with ``draws(X, n, seed, targets)`` and ``predict_stats(X)`` (a
        ``SurrogateModel``, or ``FunctionDraws`` for a known function; see the package docstring).
    targets : sequence of str
        The targets ranked.
    n : int, optional
        Base sample size of the Sobol estimates (a power of 2).
    draws : int, optional
        Draws of the surrogate the intervals and ranks are taken over.
    ranges : Design, mapping or None, optional
        The design space (``design.Design``, or the config's ``ranges``); None: the default ranges.
    seed : int, optional
        Seed of the Sobol sample and the draws.
    n_sweep : int, optional
        Points along each parameter's range for the band widths (at least 2).

    Returns
    -------
    pandas.DataFrame
        One row per (target, parameter), by decreasing ST within a target: ``band`` (the spread of
        the target, in its units, when the parameter sweeps its range, the others at the centre)
        with ``band_low``/``band_high`` and ``rank_band``; ``S1``, ``ST`` with their 95 % intervals
        and ``rank_ST``; ``noise_share`` with its interval; ``n`` and ``draws``.

    Raises
    ------
    ValueError
        If `n` is not a power of 2 or `n_sweep` < 2.
    """
    sob, sob_draws = sobol_draws(source, targets, n=n, draws=draws, ranges=ranges, seed=seed)
    band, band_draws = band_widths(source, targets, n_sweep=n_sweep, draws=draws, ranges=ranges, seed=seed)
    return ranking_table(sob, sob_draws, band, band_draws)
