"""Tests of spreadlab.experiments.sampling_study (no DEM) and of its figure."""

import numpy as np
import pandas as pd
import pytest

from spreadlab.experiments import experiment_plots as cp
from spreadlab.experiments import sampling_study as ss
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


# ---------------------------------------------------------------------------------------------
# the study with noise (map RMSE against the known truth)
# ---------------------------------------------------------------------------------------------
from spreadlab.experiments import noisy_study as ns  # noqa: E402
from spreadmap.sampling import halton_unit  # noqa: E402


def test_mfr_like_has_the_main_jobs_moments():
    y = ns.mfr_like(np.random.default_rng(0).random((200_000, 4)))  # independent of the Halton moments
    assert y.mean() == pytest.approx(0.29, abs=0.001)
    assert y.std() == pytest.approx(0.085, rel=0.01)


def test_noise_models_have_the_stated_spread():
    u = halton_unit(4096, 1)
    y = ns.mfr_like(u)
    for name, r in (("mult3", 0.03), ("mult7", 0.07)):
        obs, sd = ns.observe(u, name, np.random.default_rng(2))
        assert sd is None
        assert np.std(obs / y - 1) == pytest.approx(r, rel=0.05)
    obs, sd = ns.observe(u, "counting", np.random.default_rng(3))
    true_sd = ns.counting_sd(y, u)
    assert np.std((obs - y) / true_sd) == pytest.approx(1.0, rel=0.05)
    # 0.45/sqrt(N) with N = 76 y h/d: at y = 0.29, h/d = 2.5 the relative SD is 0.45/sqrt(55) = 6 %
    phys = np.array([[0.3, 26.0, 65.0, 10.0]])
    unit = (phys - [0.15, 10, 55, 5]) / [0.3, 40, 20, 10]
    assert ns.counting_sd(np.array([0.29]), unit)[0] / 0.29 == pytest.approx(0.45 / np.sqrt(76 * 0.29 * 2.5), rel=1e-9)
    with pytest.raises(ValueError):
        ns.observe(u, "mult5", np.random.default_rng(0))


def test_small_noisy_study_runs_and_counts_cases():
    tab = ns.run(methods=("lds", "lattice", "active"), noises=("mult7",), seeds=[0], n_max=64, batch=16,
                 n_candidates=256)
    assert set(tab["method"]) == {"lds", "lattice", "active"}
    assert np.all(np.isfinite(tab["map_rmse"])) and np.all(tab["map_rmse"] > 0)
    assert sorted(tab.loc[tab["method"] == "active", "n"]) == [32, 48, 64]
    assert sorted(tab.loc[tab["method"] == "lattice", "n"]) == [16]
    # the GP's map error with 64 LDS cases is well below the 7 % noise (0.02) and the SD (0.085)
    assert tab.loc[(tab["method"] == "lds") & (tab["n"] == 64), "map_rmse"].iloc[0] < 0.015


def test_cases_needed_and_censoring():
    tab = pd.DataFrame({"method": "lds", "noise": "mult3", "seed": [0, 0, 0, 1, 1, 1],
                        "n": [32, 48, 64] * 2, "map_rmse": [0.02, 0.009, 0.004, 0.02, 0.015, 0.011]})
    need = ns.cases_needed(tab, 0.01)
    assert list(need["n_needed"].fillna(-1)) == [48, -1]
    s = ns.summarise(need).iloc[0]
    assert s["not_reached"] == 1 and s["min"] == 48 and np.isnan(s["max"]) and s["budget"] == 64


def test_case_cost_is_the_stated_law_within_the_measured_range():
    """The scene's CPU law at hand-computed points: ln CPU = 12.099 - 1.159 f - 1.415 ln d
    - 2.403 ln(h/d) - 0.893 ln v + 1.402 ln(h/d)^2, clipped to 25-1350 s."""
    phys = np.array([[0.3, 30.0, 65.0, 10.0], [0.15, 10.0, 75.0, 5.0], [0.45, 50.0, 55.0, 15.0]])
    unit = (phys - [0.15, 10, 55, 5]) / [0.3, 40, 20, 10]
    law = lambda f, d, h, v: np.exp(12.099 - 1.159 * f - 1.415 * np.log(d) - 2.403 * np.log(h / d)  # noqa: E731
                                    - 0.893 * np.log(v) + 1.402 * np.log(h / d) ** 2)
    mid, fine, coarse = law(0.3, 30, 65, 10), law(0.15, 10, 75, 5), law(0.45, 50, 55, 15)
    assert 25 < coarse < mid < 1350 < fine  # 30 s, 48 s, 2700 s by the law
    assert np.allclose(ns.case_cost(unit), [mid, 1350.0, coarse])  # the fine corner clips to what was measured


def test_active_per_cpu_spends_less_cpu_per_case_and_records_it():
    """Same seed, same LDS start: the two active designs spend the same CPU on the start, and the
    per-CPU design's later batches cost less per case than plain ivr's."""
    tab = ns.run(methods=("active", "active_per_cpu"), noises=("counting",), seeds=[0], n_max=64, batch=16,
                 n_candidates=256)
    a = tab[tab["method"] == "active"].set_index("n")["cpu_cases"]
    b = tab[tab["method"] == "active_per_cpu"].set_index("n")["cpu_cases"]
    assert a[32] == pytest.approx(b[32])
    assert (b[64] - b[32]) < 0.7 * (a[64] - a[32])


def test_cpu_needed_and_paired_ratio():
    from spreadlab.experiments.cost_study import cpu_needed, summarise

    rows = []
    for method, cpus in (("active", [3600.0, 7200.0, 10800.0]), ("active_per_cpu", [3600.0, 5400.0, 7200.0])):
        for seed, rmse in ((0, [0.02, 0.009, 0.004]), (1, [0.02, 0.015, 0.008])):
            rows += [{"method": method, "seed": seed, "n": n, "map_rmse": e, "cpu_cases": c}
                     for n, e, c in zip((32, 48, 64), rmse, cpus)]
    need = cpu_needed(pd.DataFrame(rows), 0.01)
    assert list(need["cpu_h"]) == [2.0, 3.0, 1.5, 2.0] and list(need["cases"]) == [48, 64, 48, 64]
    s = summarise(need).set_index("method")
    assert s.loc["active_per_cpu", "ratio_active_median"] == pytest.approx((2.0 / 1.5 + 3.0 / 2.0) / 2)
    assert s.loc["active_per_cpu", "paired_seeds"] == 2 and s.loc["active", "cpu_h_median"] == 2.5
