"""The two floors' comparison (spreadlab.floors): the ratio's quantiles against independent
numbers (scipy's normal quantiles where B is exact, Monte Carlo draws otherwise), and compare() on
stand-in models of known means and SDs."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from spreadlab.floors import box_sample, by_band, compare, piles_by_band, ratio_quantile


def test_ratio_quantile_with_exact_denominator_is_the_normal_quantile_scaled():
    # B known exactly (sd 0): A / B ~ N(m_a / m_b, (s_a / m_b)^2)
    for q in (0.025, 0.5, 0.975):
        got = ratio_quantile(0.4, 0.03, 0.2, 0.0, q)
        want = stats.norm.ppf(q, loc=0.4 / 0.2, scale=0.03 / 0.2)
        assert got == pytest.approx(want, rel=1e-9)


@pytest.mark.parametrize("m_a,s_a,m_b,s_b", [(0.42, 0.02, 0.30, 0.03), (0.33, 0.01, 0.06, 0.012), (0.2, 0.05, 0.25, 0.02)])
def test_ratio_quantiles_match_monte_carlo_draws(m_a, s_a, m_b, s_b):
    rng = np.random.default_rng(1)
    n = 2_000_000
    r = rng.normal(m_a, s_a, n) / rng.normal(m_b, s_b, n)
    for q in (0.025, 0.5, 0.975):
        want = np.quantile(r, q)
        # the MC quantile's SE: sqrt(q (1 - q) / n) / density; 5e-3 relative is > 10 of them here
        assert ratio_quantile(m_a, s_a, m_b, s_b, q) == pytest.approx(want, rel=5e-3)


class _Model:
    """A stand-in map model: fixed mean and model SD per target, as functions of the point."""

    def __init__(self, means: dict, sds: dict):
        self.means, self.sds = means, sds

    def predict_stats(self, X):
        X = np.asarray(X, float)
        return {t: (self.means[t](X), self.sds[t](X), self.sds[t](X) * 2) for t in self.means}


def test_compare_on_known_means():
    frame = pd.DataFrame({"f": [0.3, 0.3, 0.3], "d_um": [50.0, 30.0, 10.0], "h_um": [55.0, 60.0, 70.0],
                          "v_mm_s": [10.0, 10.0, 10.0]})
    rough = _Model({"mfr": lambda X: np.array([0.33, 0.42, 0.50]), "pd": lambda X: np.full(len(X), 0.4)},
                   {"mfr": lambda X: np.full(len(X), 0.01), "pd": lambda X: np.full(len(X), 0.01)})
    flat = _Model({"mfr": lambda X: np.array([0.01, 0.30, 0.45]), "pd": lambda X: np.full(len(X), 0.4)},
                  {"mfr": lambda X: np.array([0.01, 0.0, 0.02]), "pd": lambda X: np.full(len(X), 0.01)})
    out = compare(rough, flat, frame, ["mfr", "pd"])
    assert out["h_over_d"].tolist() == pytest.approx([1.1, 2.0, 7.0])
    # flat MFR 0.01 +- 0.01: its interval reaches 0, no ratio
    assert out["mfr_ratio_defined"].tolist() == [False, True, True]
    assert np.isnan(out.loc[0, "mfr_ratio"])
    # exact denominator: the ratio interval is the numerator's, scaled
    z = stats.norm.ppf(0.975)
    assert out.loc[1, "mfr_ratio"] == pytest.approx(0.42 / 0.30, rel=1e-6)
    assert out.loc[1, "mfr_ratio_lo"] == pytest.approx((0.42 - z * 0.01) / 0.30, rel=1e-6)
    assert out.loc[1, "mfr_diff"] == pytest.approx(0.12)
    assert out.loc[2, "mfr_diff_hi"] - out.loc[2, "mfr_diff"] == pytest.approx(z * np.hypot(0.01, 0.02))
    # equal means: the ratio's interval holds 1, the difference's holds 0
    assert (out["pd_ratio_lo"] < 1).all() and (out["pd_ratio_hi"] > 1).all()
    assert out["pd_ratio"].tolist() == pytest.approx([1.0, 1.0, 1.0], rel=1e-6)
    bands = by_band(out, "mfr", edges=(1.0, 1.5, 3.0, 8.0))
    assert bands["points"].tolist() == [1, 1, 1] and bands["ratio_defined"].tolist() == [0, 1, 1]


def test_box_sample_fills_the_box():
    box = box_sample(256, seed=3)
    assert len(box) == 256
    assert box["d_um"].between(10, 50).all() and box["h_um"].between(55, 75).all()
    # scrambled Sobol': every quarter of each range holds a quarter of the points
    for col, lo, hi in (("f", 0.15, 0.45), ("v_mm_s", 5, 15)):
        counts = np.histogram(box[col], bins=np.linspace(lo, hi, 5))[0]
        assert counts.tolist() == [64, 64, 64, 64]


def test_piles_by_band_tells_a_drained_pile_from_an_unsteady_flow():
    """Hand-made sweep: per h/d band the counts, the flags split by the heap left at the window's
    end against the bound (a missing heap counts as ran down), and the rolled-off statistics."""
    rows = [  # d_um, h_um, status, flagged, heap_end_h2, rolled off, spheres, mfr
        (50, 55, "ok", True, 0.3, 150, 300, 0.05),     # h/d 1.1: ran down
        (50, 60, "ok", True, 3.5, 100, 400, 0.08),     # h/d 1.2: unsteady with the heap full
        (50, 65, "ok", False, 3.4, 20, 400, 0.10),     # h/d 1.3
        (40, 70, "ok", True, float("nan"), 10, 500, 0.2),  # h/d 1.75: no heap measured: ran down
        (40, 70, "failed", False, float("nan"), 0, 500, float("nan")),
        (10, 75, "ok", False, 2.2, 272, 4000, 0.5),    # h/d 7.5
    ]
    cases = pd.DataFrame(rows, columns=["d_um", "h_um", "status", "flagged", "heap_end_h2", "rolled_off_particles",
                                        "n_particles", "mfr"])
    t = piles_by_band(cases, 0.7, edges=(1.0, 1.5, 2.0, 8.0)).set_index("h_over_d_from")
    counts = ["cases", "finished", "flagged", "flagged_ran_down", "flagged_unsteady_heap_full"]
    assert t.loc[1.0, counts].tolist() == [3, 3, 2, 1, 1]
    assert t.loc[1.0, "rolled_off_median"] == 100 and t.loc[1.0, "rolled_off_max"] == 150
    assert t.loc[1.0, "rolled_off_share_median"] == 0.25  # 150/300, 100/400, 20/400
    assert t.loc[1.0, "heap_end_h2_min"] == 0.3 and t.loc[1.0, "mfr_median"] == 0.10  # the one usable case
    assert t.loc[1.5, ["cases", "finished", "flagged", "flagged_ran_down"]].tolist() == [2, 1, 1, 1]
    assert np.isnan(t.loc[1.5, "mfr_median"])
    assert t.loc[2.0, ["cases", "flagged", "rolled_off_max", "heap_end_h2_median"]].tolist() == [1, 0, 272, 2.2]
