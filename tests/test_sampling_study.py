"""Tests of spreadmap.convergence.sampling_study (no DEM) and of its figure."""
import json

import numpy as np
import pandas as pd
import pytest

from spreadmap.convergence import plots as cp
from spreadmap.convergence import sampling_study as ss
from spreadmap.design import bounds


def test_designs():
    lat = ss.lattice_points(3)
    assert lat.shape == (81, 4)
    assert set(np.unique(lat)) == {0.0, 0.5, 1.0}  # end points included
    assert len(np.unique(lat, axis=0)) == 81
    # LDS: case i is the same point whatever the total
    np.testing.assert_array_equal(ss.lds_points(50, 3), ss.lds_points(500, 3)[:50])
    assert not np.array_equal(ss.lds_points(50, 3), ss.lds_points(50, 4))
    np.testing.assert_array_equal(ss.random_points(50, 3), ss.random_points(500, 3)[:50])
    for f in ss.TEST_FUNCTIONS.values():
        y = f(ss.lds_points(256, 0))
        assert y.shape == (256,) and np.all(np.isfinite(y)) and np.std(y) > 0


@pytest.fixture(scope="module")
def small_study():
    return ss.study(functions={"flow_curve": ss.flow_curve}, seeds=4, k_max=9)


def test_study_results_are_finite_and_deterministic(small_study):
    tab = small_study.table
    assert list(tab.columns) == ["function", "method", "schedule", "seed", "n_converged",
                                 "n_first_holds", "budget"]
    # one lattice run, and for each of 4 seeds LDS and random under both schedules
    assert len(tab) == 1 + 4 * 2 * 2
    assert (tab["budget"] == 9**4).all()
    lds = tab[tab["method"] == "lds"]
    assert np.all(np.isfinite(lds["n_converged"]))
    assert lds["n_converged"].between(16, 9**4).all()
    assert (lds["n_first_holds"] <= lds["n_converged"]).all()
    # the lattice-sizes schedule can only stop on lattice sizes
    on_sizes = tab[tab["schedule"] == "lattice_sizes"]["n_converged"].dropna()
    assert set(on_sizes) <= {k**4 for k in range(3, 10)}
    again = ss.run_study(functions={"flow_curve": ss.flow_curve}, seeds=4, k_max=9)
    pd.testing.assert_frame_equal(tab, again)


def test_lds_beats_random_on_the_same_steps(small_study):
    """Measured: on the k^4 schedule LDS converges within 4096 cases for every seed, random
    sampling within none of them (its prefix statistics still move ~ 1/sqrt(N))."""
    tab = small_study.table
    on = tab[tab["schedule"] == "lattice_sizes"]
    lds = on[on["method"] == "lds"].set_index("seed")["n_converged"]
    rnd = on[on["method"] == "random"].set_index("seed")["n_converged"].fillna(np.inf)
    assert (lds <= 4096).all()
    assert (lds < rnd).all()
    row = small_study.ratios.set_index("schedule").loc["lattice_sizes"]
    assert row["random_over_lds_kind"] == "lower bound"  # random median censored at the budget
    assert row["random_over_lds"] >= 6561 / 4096


def test_case_by_case_check_hardly_separates_lds_from_random(small_study):
    """Measured: checked after every added case, LDS and random need about as many cases
    (the change of one added case scales like 1/N for any design)."""
    row = small_study.ratios.set_index("schedule").loc["case"]
    assert row["random_over_lds_kind"] == "ratio"
    assert 1 / 3 < row["random_over_lds"] < 3


def test_predictor_gets_physical_units_and_both_outputs_count():
    seen = []

    def predict(points):
        seen.append(points)
        f, d, h, v = points.T
        mfr = 0.6 * (1 - np.exp(-(h / d - 1)))
        pd_ = 0.55 + 0.05 * np.tanh(f - 0.3) + 0.001 * v
        return np.column_stack([mfr, pd_])

    tab = ss.run_study(functions={}, predictor=predict, seeds=[5], k_max=5)
    assert set(tab["function"]) == {"predictor"}
    pts = np.concatenate(seen)
    low, high = bounds()
    assert np.all(pts >= low - 1e-12) and np.all(pts <= high + 1e-12)
    assert pts[:, 1].max() > 40 and pts[:, 2].min() < 60  # really physical (um), not [0, 1]
    assert np.isfinite(tab.loc[tab["method"] == "lds", "n_converged"]).any()


def test_summary_medians_censoring_and_ratios():
    rows = [("g", "lattice", "lattice_sizes", pd.NA, 10000.0)]
    rows += [("g", "lds", "case", s, n) for s, n in enumerate([900.0, 1000.0, 1100.0, 1200.0])]
    rows += [("g", "random", "case", s, n) for s, n in enumerate([2000.0, np.nan, np.nan, np.nan])]
    tab = pd.DataFrame(rows, columns=["function", "method", "schedule", "seed", "n_converged"])
    tab["budget"] = 10000
    summ = ss.summarise(tab).set_index(["method", "schedule"])
    assert summ.loc[("lds", "case"), "median"] == 1000.0  # lower median of four
    assert summ.loc[("lds", "case"), "iqr"] == 200.0
    assert np.isnan(summ.loc[("random", "case"), "median"])  # 3 of 4 censored
    assert summ.loc[("random", "case"), "not_converged"] == 3
    assert summ.loc[("lattice", "lattice_sizes"), "iqr"] == 0.0
    rat = ss.ratios(summ.reset_index()).iloc[0]
    assert rat["lattice_over_lds"] == pytest.approx(10.0) and rat["lattice_over_lds_kind"] == "ratio"
    assert rat["random_over_lds"] == pytest.approx(10.0)
    assert rat["random_over_lds_kind"] == "lower bound"


def test_sampling_study_plot_writes_files(small_study, tmp_path):
    paths = cp.plot_sampling_study(small_study.table, tmp_path / "fig" / "sampling_study")
    for ext in ("png", "pdf", "csv"):
        assert paths[ext].exists() and paths[ext].stat().st_size > 0
    data = pd.read_csv(paths["csv"])
    assert {"function", "method", "n_converged", "median", "iqr"} <= set(data.columns)
    assert len(data) == len(small_study.table)
