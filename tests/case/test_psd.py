"""The size distribution's numbers (spreadmap.case.psd) against independent ones: scipy's
log-normal, numerical integration, and the span's definition."""
import math

import numpy as np
import pytest
from scipy import integrate, stats

from spreadmap.case import psd
from spreadmap.metrics.sizes import volume_quantile

TAILS = [0.05, 0.95]


@pytest.mark.parametrize("span", [0.3, 1.0, 1.8])
def test_the_untruncated_quantiles_give_back_the_span(span):
    """span = (D90 - D10) / D50 of the volume distribution, read off scipy's log-normal."""
    dist = stats.lognorm(s=psd.log_sd(span), scale=30.0)
    assert (dist.ppf(0.9) - dist.ppf(0.1)) / dist.ppf(0.5) == pytest.approx(span, rel=1e-12)


@pytest.mark.parametrize("span", [0.5, 1.0])
def test_truncated_quantiles_and_cdf_against_scipy(span):
    sigma = psd.log_sd(span)
    dist = stats.lognorm(s=sigma, scale=30.0)
    for q in (0.0, 0.1, 0.5, 0.9, 1.0):
        want = dist.ppf(TAILS[0] + q * (TAILS[1] - TAILS[0]))
        assert psd.quantile(30.0, span, TAILS, q) == pytest.approx(want, rel=1e-9)
        assert psd.volume_cdf(want, 30.0, span, TAILS) == pytest.approx(q, abs=1e-9)
    sizes, fractions = psd.sieve_table(30.0, span, TAILS)
    assert len(sizes) == psd.SIEVES and fractions[0] == 0.0 and fractions[-1] == 1.0
    assert np.all(np.diff(sizes) > 0)


@pytest.mark.parametrize("span", [0.5, 1.0, 1.8])
def test_number_cdf_is_the_volume_distribution_weighted_by_d_cubed(span):
    """The number CDF against a numerical integral of the volume density over D^3."""
    sigma = psd.log_sd(span)
    dist = stats.lognorm(s=sigma, scale=30.0)
    lo, hi = psd.quantile(30.0, span, TAILS, 0.0), psd.quantile(30.0, span, TAILS, 1.0)
    total = integrate.quad(lambda x: dist.pdf(x) / x ** 3, lo, hi)[0]
    for x in np.linspace(lo, hi, 7):
        part = integrate.quad(lambda y: dist.pdf(y) / y ** 3, lo, x)[0]
        assert psd.number_cdf(x, 30.0, span, TAILS) == pytest.approx(part / total, abs=1e-9)


@pytest.mark.parametrize("span", [0.5, 1.0, 1.8])
def test_mean_volume_ratio_against_integration(span):
    """A sphere's mean volume by number over a D50 sphere's: (mass per unit volume fraction) / (count)."""
    dist = stats.lognorm(s=psd.log_sd(span), scale=1.0)
    lo, hi = psd.quantile(1.0, span, TAILS, 0.0), psd.quantile(1.0, span, TAILS, 1.0)
    volume = integrate.quad(dist.pdf, lo, hi)[0]
    count = integrate.quad(lambda x: dist.pdf(x) / x ** 3, lo, hi)[0]
    assert psd.mean_volume_ratio(span, TAILS) == pytest.approx(volume / count, rel=1e-8)


def test_one_size_is_no_table():
    assert psd.sieve_table(30e-6, 0.0, TAILS) == ([], [])
    assert psd.mean_volume_ratio(0.0, TAILS) == 1.0
    assert psd.quantile(30e-6, 0.0, TAILS, 0.9) == 30e-6


@pytest.mark.parametrize("tails", [[0.5, 0.9], [0.0, 0.95], [0.1, 1.0], [0.6, 0.4]])
def test_bad_tails_are_refused(tails):
    with pytest.raises(ValueError, match="tails"):
        psd.sieve_table(30.0, 1.0, tails)


def test_volume_quantile_of_two_sizes():
    """Eight spheres of d 1 and one of d 2: equal volumes, so half the volume lies below the
    midpoint between the small spheres' share and the large one's."""
    d = [1.0] * 8 + [2.0]
    assert volume_quantile(d, 0.2) == 1.0
    assert volume_quantile(d, 0.8) == 2.0
    assert 1.0 < volume_quantile(d, 0.5) < 2.0
    assert volume_quantile([3.0, 3.0], 0.1) == 3.0
    assert math.isnan(volume_quantile([], 0.5))
