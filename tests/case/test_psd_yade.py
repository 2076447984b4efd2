"""A powder with a size distribution, on the real YADE binary (smoke preset): the sizes makeCloud
places follow the requested distribution, the time step is the smallest sphere's, and at a gap
thinner than D90 the coarse tail cannot pass: the layer is finer than the feed and no sphere
larger than the gap lies in it. (Span 0 reproducing the one-size scene to the bit is
tests/case/test_reproduce_published_yade.py's.)"""
import copy

import numpy as np
import pytest
from conftest import case_params, run_many
from scipy import stats

from spreadmap.case import psd
from spreadmap.case.scene import rayleigh_time_step
from spreadmap.metrics import case_metrics
from spreadmap.metrics.sizes import volume_quantile

pytestmark = pytest.mark.yade

SPAN, TAILS = 1.0, [0.05, 0.95]  # a 15-45 um-like powder at D50 30 um: D10 20, D90 45 um (truncated)
MEDIUM = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}
COARSE_THIN = {"f": 0.45, "d_um": 45.0, "h_um": 55.0, "v_mm_s": 10.0}  # gap / D90 0.81


def with_span(config: dict, span: float) -> dict:
    out = copy.deepcopy(config)
    out["material"]["size_distribution"] = {"span": span, "tails": TAILS}
    return out


@pytest.fixture(scope="module")
def runs(config, tmp_path_factory):
    cfg = with_span(config, SPAN)
    poured = case_params(cfg, MEDIUM, "smoke", stop_after="settle")
    spread = case_params(cfg, COARSE_THIN, "smoke")
    results = run_many([(poured, tmp_path_factory.mktemp("poured")), (spread, tmp_path_factory.mktemp("thin"))])
    return {"poured": (poured, *results[0]), "thin": (spread, *results[1])}


def test_placed_sizes_follow_the_requested_distribution(runs):
    params, result, raw = runs["poured"]
    assert result["outcome"] == "ok", result
    d = 2.0 * np.asarray(raw["snapshots"]["settled"]["radii"])
    assert len(d) == params["n_particles"]
    d50 = MEDIUM["d_um"] * 1e-6
    number_cdf = np.vectorize(lambda x, span: psd.number_cdf(x, d50, span, TAILS))
    # counted by number, the sizes are the truncated log-normal's (KS at the 1 % level) ...
    assert stats.kstest(d, lambda x: number_cdf(x, SPAN)).pvalue > 0.01
    # ... and the test tells them from a narrower powder's
    assert stats.kstest(d, lambda x: number_cdf(x, 0.5)).pvalue < 0.01
    # by volume, the certificate's quantiles within 3 % (makeCloud's strata of ~200 spheres)
    for q in (0.1, 0.5, 0.9):
        assert volume_quantile(d, q) == pytest.approx(psd.quantile(d50, SPAN, TAILS, q), rel=0.03), q
    # nothing outside the cut tails
    assert d.min() >= params["psd_sizes"][0] * (1 - 1e-9) and d.max() <= params["psd_sizes"][-1] * (1 + 1e-9)


def test_the_time_step_is_the_smallest_spheres(runs, config):
    params, _, raw = runs["poured"]
    smallest = params["psd_sizes"][0]
    want = rayleigh_time_step(0.5 * smallest, params["density"], params["young"], params["poisson"])
    assert raw["critical_time_step"] == pytest.approx(want, rel=1e-12)
    assert raw["time_step_ratio"] == pytest.approx(config["presets"]["smoke"]["dt_factor"])
    # Rayleigh's step is proportional to the radius: the D5 sphere's, not the D50's
    d50_step = rayleigh_time_step(0.5 * MEDIUM["d_um"] * 1e-6, params["density"], params["young"], params["poisson"])
    assert raw["critical_time_step"] / d50_step == pytest.approx(smallest / (MEDIUM["d_um"] * 1e-6), rel=1e-12)


def test_a_gap_thinner_than_d90_lets_only_the_finer_spheres_through(runs, config):
    params, result, raw = runs["thin"]
    assert result["outcome"] == "ok", result
    m = case_metrics(raw, config["regime"], config["stability"], config["metrics"])
    print({k: m[k] for k in ("mfr", "pd", "regime", "coverage", "thickness_ratio", "h_over_d90", "layer_d50_ratio",
                             "layer_d50_ratio_sd", "peak_overlap_free", "peak_overlap_wedged", "flag_reason")})
    assert m["h_over_d90"] < 1.0
    assert m["escaped_particles"] == 0
    # the deposit is finer than the feed, by more than twice its bootstrap SD (a smoke layer holds few spheres) ...
    assert m["layer_d50_ratio"] + 2.0 * m["layer_d50_ratio_sd"] < 1.0
    # ... and the coarse tail stays behind: among the spheres that passed under the blade (from its
    # start at x = 0 to its rear face), none is larger than a sphere squeezed through the gap at the
    # wedge bound can be (each of its two contacts, blade and floor, compressed by at most
    # max_wedge_overlap_ratio x R: D (1 - bound) <= h) while the feed holds such spheres, and the
    # largest that passed is below the feed's D90 (at x1000 the contacts are soft: a sphere 5 % above
    # the gap passed, 2026-12-06)
    end = raw["snapshots"]["window_end"]
    pos, d = np.asarray(end["positions"]), 2.0 * np.asarray(end["radii"])
    passed = d[(pos[:, 0] > 0.0) & (pos[:, 0] < end["blade_rear_x"])]
    feed = 2.0 * np.asarray(raw["snapshots"]["blade_start"]["radii"])
    squeeze = params["gap"] / (1.0 - config["stability"]["max_wedge_overlap_ratio"])
    assert len(passed) > 10 and passed.max() < squeeze < feed.max()
    assert passed.max() < volume_quantile(feed, 0.9)
    # and the case reads as a poor layer: not the normal regime
    assert m["regime"] in ("short_feed", "jamming")
