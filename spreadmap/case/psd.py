"""A powder's particle size distribution (PSD) as the scene places it.

A gas-atomised metal powder's certificate gives volume-based quantiles (laser diffraction: D10, D50,
D90). The scene's powder is a log-normal distribution by volume, given by its D50 (the design
point's ``d_um``) and its span (D90 - D10) / D50, truncated at two volume quantiles (the tails, e.g.
D5 and D95) and renormalised between them. With the volume-based log-normal of median D50 and
log-SD sigma, span = 2 sinh(z90 sigma) (z90 the standard normal's 0.9 quantile), so
sigma = asinh(span / 2) / z90.

The same distribution counted by number is log-normal with median D50 exp(-3 sigma^2) and the same
sigma (weighting a log-normal density by D^-3 shifts its log-mean by -3 sigma^2), truncated at the
same diameters: what the scene's sphere count and the KS test of the placed sizes use.

YADE's makeCloud takes the distribution as sieve sizes and cumulative volume fractions
(``psdSizes``, ``psdCumm``, ``distributeMass=True``) and places a stratified set of sizes, the
cumulative fractions interpolated linearly between the sieves (tests/case/test_psd_yade.py measures
what it places against this module). A span of 0 is one size: no table, the scene's one-size path.
"""
from __future__ import annotations

import math
from statistics import NormalDist

STANDARD_NORMAL = NormalDist()
Z90 = STANDARD_NORMAL.inv_cdf(0.9)
SIEVES = 41  # sieve sizes of the table makeCloud receives: equal steps of volume fraction


def log_sd(span: float) -> float:
    """The log-normal's sigma for a span (D90 - D10) / D50 of its volume distribution (untruncated)."""
    if not (math.isfinite(span) and span >= 0.0):
        raise ValueError(f"span {span!r} must be a finite number >= 0")
    return math.asinh(0.5 * span) / Z90


def _check_tails(tails) -> tuple[float, float]:
    low, high = (float(t) for t in tails)
    if not 0.0 < low < 0.5 < high < 1.0:
        raise ValueError(f"tails {list(tails)!r} must be two volume quantiles with 0 < low < 0.5 < high < 1")
    return low, high


def quantile(d50: float, span: float, tails, q: float) -> float:
    """The diameter below which a volume fraction q of the truncated distribution lies (D_q), in the
    unit of d50."""
    low, high = _check_tails(tails)
    if not 0.0 <= q <= 1.0:
        raise ValueError(f"quantile {q!r} must lie in [0, 1]")
    if span == 0.0:
        return d50
    return d50 * math.exp(log_sd(span) * STANDARD_NORMAL.inv_cdf(low + q * (high - low)))


def sieve_table(d50: float, span: float, tails) -> tuple[list[float], list[float]]:
    """Sieve sizes (diameters, the unit of d50) and their cumulative volume fractions, 0 to 1: SIEVES
    sizes at equal steps of volume fraction between the tails. Empty lists for a span of 0."""
    _check_tails(tails)
    if span == 0.0:
        return [], []
    fractions = [i / (SIEVES - 1) for i in range(SIEVES)]
    return [quantile(d50, span, tails, q) for q in fractions], fractions


def volume_cdf(diameter: float, d50: float, span: float, tails) -> float:
    """The volume fraction of the truncated distribution below `diameter`."""
    low, high = _check_tails(tails)
    sigma = log_sd(span)
    if sigma == 0.0:
        return float(diameter >= d50)
    p = STANDARD_NORMAL.cdf(math.log(diameter / d50) / sigma)
    return min(1.0, max(0.0, (p - low) / (high - low)))


def number_cdf(diameter: float, d50: float, span: float, tails) -> float:
    """The number fraction of the truncated distribution's spheres below `diameter`: the log-normal
    by number (median D50 exp(-3 sigma^2)) between the same truncation diameters."""
    low, high = _check_tails(tails)
    sigma = log_sd(span)
    if sigma == 0.0:
        return float(diameter >= d50)
    shift = 3.0 * sigma  # in units of sigma: ln D50_n = ln D50 - 3 sigma^2
    a, b = STANDARD_NORMAL.inv_cdf(low) + shift, STANDARD_NORMAL.inv_cdf(high) + shift
    z = math.log(diameter / d50) / sigma + shift
    z = min(max(z, a), b)
    return (STANDARD_NORMAL.cdf(z) - STANDARD_NORMAL.cdf(a)) / (STANDARD_NORMAL.cdf(b) - STANDARD_NORMAL.cdf(a))


def mean_volume_ratio(span: float, tails) -> float:
    """A sphere's mean volume (counted by number) over the volume of a D50 sphere, exact for the
    truncated log-normal: 1 / E_v[(D50/D)^3], with E_v[(D/D50)^-3] = exp(9 sigma^2 / 2)
    (Phi(b + 3 sigma) - Phi(a + 3 sigma)) / (Phi(b) - Phi(a)), a and b the tails' standard normal
    quantiles. 1 for one size. The scene places volume / (this x the D50 sphere's volume) spheres."""
    low, high = _check_tails(tails)
    sigma = log_sd(span)
    if sigma == 0.0:
        return 1.0
    a, b = STANDARD_NORMAL.inv_cdf(low), STANDARD_NORMAL.inv_cdf(high)
    phi = STANDARD_NORMAL.cdf
    inverse_cube = math.exp(4.5 * sigma ** 2) * (phi(b + 3.0 * sigma) - phi(a + 3.0 * sigma)) / (phi(b) - phi(a))
    return 1.0 / inverse_cube
