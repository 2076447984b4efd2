"""Rank the four design parameters by their influence, with the surrogate's uncertainty carried.

``bands``: the study's band widths (spread of a target when one parameter sweeps its range, the
others at the centre); ``sobol``: first-order and total Sobol indices (``scipy.stats.sobol_indices``)
with the noise share; ``ranking``: ranks only where draws separate the parameters; ``ranking_plot``.

A *draw source* is anything with ``draws(X, n, seed, targets) -> {target: (n, len(X))}``
(``SurrogateModel``: GP posterior samples or MLP ensemble members) and ``noise_sd`` per target
through ``predict_stats``; ``FunctionDraws`` wraps a known function for tests and comparisons.
"""
from .bands import band_widths
from .draws import FunctionDraws
from .ranking import rank_by_draws, ranking_table, sensitivity
from .ranking_plot import plot_ranking
from .sobol import sobol_draws

__all__ = ["band_widths", "plot_ranking", "sobol_draws", "rank_by_draws", "ranking_table", "sensitivity", "FunctionDraws"]
