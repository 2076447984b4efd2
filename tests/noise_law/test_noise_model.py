"""The noise law fitted to seed repeats (spreadmap.noise_law, issue 32): the fit recovers a known
law from synthetic seed repeats (normal seeds about a known SD, so each cell's variance carries
real chi-square noise), its profile intervals cover the truth at about their nominal rate, the
held-out check flags a law whose scale is wrong, the law goes into a results table as configured,
and docs/noise's published law recomputes from the published tables."""
import json
import math

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT

from spreadlab.noise_law.cells import published_cells, seed_cells
from spreadlab.noise_law.fit import HD_REF, LAW, N_REF, fit_law, likelihood_ratio, profile_interval
from spreadlab.noise_law.leave_one_out import leave_point_out, predictive_check, scored
from spreadmap.config import check_sections
from spreadmap.metrics.noise import calibrated_noise
from spreadmap.noise_law.apply import case_noise

TRUTH = {"a": math.log(0.03), "b_ln_n": -0.5, "g_ln_hd": -0.8}


def true_rel_sd(n, h_over_d, truth=TRUTH):
    return np.exp(truth["a"] + truth["b_ln_n"] * np.log(n / N_REF) + truth["g_ln_hd"] * np.log(h_over_d / HD_REF))


def synthetic_cases(rng, points=60, truth=TRUTH) -> pd.DataFrame:
    """Seed repeats at random points: each point's h/d, N and mean drawn, 2-4 seeds (k - 1 = 1-3
    dof, as published) whose values are normal about the mean with the true SD."""
    rows = []
    for i in range(points):
        d = rng.uniform(10, 50)
        h = d * math.exp(rng.uniform(math.log(1.1), math.log(6.0)))
        n = math.exp(rng.uniform(math.log(8), math.log(600)))
        mean = rng.uniform(0.3, 0.55)
        sd = mean * true_rel_sd(n, h / d, truth)
        for seed in range(1, int(rng.integers(3, 5)) + (1 if i % 5 == 0 else 0)):
            mfr, pd_ = rng.normal(mean, sd, 2)
            rows.append({"case_id": f"p{i}-s{seed}", "f": 0.3, "d_um": d, "h_um": h, "v_mm_s": 10.0, "seed": seed,
                         "status": "ok", "flagged": False, "mfr": mfr, "pd": pd_, "n_passed": n, "n_pd": n,
                         "mfr_sd": 0.37 / math.sqrt(n) * mfr, "pd_sd": 0.37 / math.sqrt(n) * pd_})
    return pd.DataFrame(rows).assign(source="synthetic", variant="default")


def synthetic_cells(rng, points=60, truth=TRUTH) -> pd.DataFrame:
    cells = seed_cells(synthetic_cases(rng, points, truth))
    return cells[cells["target"] == "mfr"].reset_index(drop=True)


def test_the_fit_recovers_a_known_law_from_seed_repeats():
    cells = synthetic_cells(np.random.default_rng(1), points=150)
    assert set(cells["dof"]) == {1, 2, 3}
    law = fit_law(cells)
    se = np.sqrt(np.diag(law.cov))
    for k, term in enumerate(LAW):
        assert abs(law.coef[k] - TRUTH[term]) < 3.5 * se[k], (term, law.coef[k], se[k])
        lo, hi = profile_interval(cells, law, term)
        assert lo < law.coef[k] < hi
        # the profile interval of a log-linear Gamma model is close to the Wald one
        assert 0.7 < (hi - lo) / (2 * 1.96 * se[k]) < 1.3
    assert se[1] < 0.1 and se[2] < 0.15  # informative at 150 points
    # the counting exponent is what the law holds: its test does not reject it here
    restricted = fit_law(cells, LAW, {"b_ln_n": -0.5})
    assert restricted.coefficient("b_ln_n") == -0.5 and restricted.terms == ("a", "g_ln_hd")
    assert likelihood_ratio(cells, law, restricted)[2] > 0.001


def test_the_test_of_the_counting_exponent_rejects_a_wrong_one():
    cells = synthetic_cells(np.random.default_rng(2), points=150, truth={**TRUTH, "b_ln_n": -0.2})
    law = fit_law(cells)
    p = likelihood_ratio(cells, law, fit_law(cells, LAW, {"b_ln_n": -0.5}))[2]
    assert p < 1e-4
    assert profile_interval(cells, law, "b_ln_n")[0] > -0.5


def test_profile_intervals_cover_the_truth_at_about_their_nominal_rate():
    """40 independent synthetic studies of 60 points: each coefficient's 95 % profile interval covers
    the truth in 120 tries about 95 % of the time (binomial 99 % range of 120 x 0.95: 108-119)."""
    rng = np.random.default_rng(7)
    hits = total = 0
    for _ in range(40):
        cells = synthetic_cells(rng, points=60)
        law = fit_law(cells)
        for term in LAW:
            lo, hi = profile_interval(cells, law, term)
            hits += lo <= TRUTH[term] <= hi
            total += 1
    assert 108 <= hits <= 119, (hits, total)


def test_the_held_out_check_is_consistent_for_the_true_law_and_flags_a_wrong_scale():
    cells = synthetic_cells(np.random.default_rng(3), points=80)
    truth_sd = cells["mean"] * true_rel_sd(cells["n"], cells["h_over_d"])
    right = predictive_check(scored(cells.assign(sd_pred=truth_sd)))
    assert right["verdict"] == "consistent" and right["coverage_verdict"] == "consistent"
    assert right["ratio_chi2_lo"] < 1 < right["ratio_chi2_hi"]
    held = predictive_check(leave_point_out(cells))
    assert held["verdict"] == "consistent" and held["coverage_verdict"] == "consistent"
    too_big = predictive_check(scored(cells.assign(sd_pred=1.6 * truth_sd)))
    assert too_big["verdict"] == "too wide" and too_big["ratio_boot_hi"] < 1 and too_big["coverage_verdict"] == "too wide"
    assert too_big["ks_p"] < 0.01
    too_small = predictive_check(scored(cells.assign(sd_pred=0.6 * truth_sd)))
    assert too_small["verdict"] == "too narrow" and too_small["coverage_verdict"] == "too narrow"
    # a law fitted on these cells, its scale then set wrong, held out: flagged
    wrong = leave_point_out(cells).assign(sd_pred=lambda c: 1.5 * c["sd_pred"])
    assert predictive_check(scored(wrong))["verdict"] == "too wide"


def test_a_held_out_point_is_predicted_by_the_law_fitted_without_it():
    cells = synthetic_cells(np.random.default_rng(4), points=30)
    point = cells["point"].iloc[0]
    spoiled = cells.copy()
    spoiled.loc[spoiled["point"] == point, "s2"] *= 100.0  # the point's own variance must not move its prediction
    held = leave_point_out(spoiled)
    mine = spoiled["point"] == point
    np.testing.assert_allclose(held.loc[mine, "sd_pred"], fit_law(cells[~mine]).sd(cells[mine]), rtol=1e-8)
    assert (held.loc[mine, "u"] > 10).all()


NOISE_MODEL = {"n_ref": 150.0, "h_over_d_ref": 2.0,
               "mfr": {"rel_sd": 0.03, "n_exponent": -0.4, "h_over_d_exponent": -0.8},
               "pd": {"rel_sd": 0.031, "n_exponent": -0.5, "h_over_d_exponent": -0.9}}


def results_table() -> pd.DataFrame:
    # h/d: 1.2, 3.0, 2.0 (jammed: nothing passed), 2.0 (failed)
    return pd.DataFrame({"case_id": list("abcd"), "d_um": [50.0, 20.0, 30.0, 30.0], "h_um": [60.0, 60.0, 60.0, 60.0],
                         "mfr": [0.3, 0.5, 0.0, np.nan], "pd": [0.28, 0.45, 0.01, np.nan],
                         "n_passed": [150.0, 300.0, 0.0, np.nan], "n_pd": [120.0, 250.0, 0.5, np.nan],
                         "mfr_sd": [0.009, 0.0107, 0.37 * 0.002, np.nan], "pd_sd": [0.0095, 0.0105, 0.37 * 0.02, np.nan],
                         "coverage_sd": [0.01, 0.01, 0.01, np.nan], "mfr_sd_within": [0.5] * 4})


def test_the_law_sets_each_case_noise_sd_of_mfr_and_pd_and_the_bands_the_layer_measures():
    table = results_table()
    bands = [{"h_over_d_below": 2.0, "factor": 1.37, "targets": ["layer_fill", "coverage", "roughness_d", "thickness_ratio"]}]
    out = case_noise(table, NOISE_MODEL, bands)
    m, p = NOISE_MODEL["mfr"], NOISE_MODEL["pd"]
    np.testing.assert_allclose(out["mfr_sd"][:2], [0.3 * 0.03 * (1.2 / 2) ** -0.8, 0.5 * 0.03 * 2 ** -0.4 * 1.5 ** -0.8])
    np.testing.assert_allclose(out["pd_sd"][:2], [0.28 * 0.031 * 0.8 ** -0.5 * 0.6 ** -0.9,
                                                  0.45 * 0.031 * (250 / 150) ** -0.5 * 1.5 ** -0.9])
    # nothing passed: one sphere's worth (read off the stated SD) times the law at N = 1
    np.testing.assert_allclose(out["mfr_sd"][2], 0.002 * m["rel_sd"] * (1 / 150) ** m["n_exponent"])
    # half a sphere in the box: per sphere = PD / n, at N = 1
    np.testing.assert_allclose(out["pd_sd"][2], 0.01 / 0.5 * p["rel_sd"] * (1 / 150) ** p["n_exponent"])
    assert out[["mfr_sd", "pd_sd"]].iloc[3].isna().all()
    np.testing.assert_allclose(out["coverage_sd"][:3], [0.0137, 0.01, 0.01])  # the band, for the layer measures
    pd.testing.assert_series_equal(out["mfr_sd_within"], table["mfr_sd_within"])
    pd.testing.assert_series_equal(out["mfr"], table["mfr"])
    assert table["mfr_sd"][0] == 0.009  # the input is left as it was


def test_without_a_law_the_bands_apply_as_before_and_a_band_beside_the_law_is_refused():
    table = results_table()
    published_bands = [{"h_over_d_below": 2.0, "factor": 1.37}, {"h_over_d_from": 3.0, "factor": 0.61, "targets": ["mfr", "pd"]}]
    pd.testing.assert_frame_equal(case_noise(table, None, published_bands), calibrated_noise(table, published_bands))
    with pytest.raises(ValueError, match=r"noise_calibration\[0\] scales \['mfr', 'pd'\].*without `targets` scales every target"):
        check_sections(NOISE_MODEL, published_bands)
    with pytest.raises(ValueError, match=r"noise_calibration\[0\] scales \['pd'\]"):
        case_noise(table, NOISE_MODEL, [{"h_over_d_from": 3.0, "factor": 0.6, "targets": ["pd", "coverage"]}])
    with pytest.raises(ValueError, match="no `n_pd` column"):
        case_noise(table.drop(columns="n_pd"), NOISE_MODEL, [])


def test_the_published_law_recomputes_from_the_published_seed_repeats():
    """docs/noise (tools/fit_noise_model.py): the cells and the law's coefficients from the tables."""
    published = json.loads((ROOT / "docs" / "noise" / "law.json").read_text())
    shipped, other = published_cells(ROOT / "docs")
    cells = pd.read_csv(ROOT / "docs" / "noise" / "cells.csv")
    assert len(cells[cells["role"] == "fit"]) == len(shipped) and len(cells[cells["role"] == "check"]) == len(other)
    for target in ("mfr", "pd"):
        part = shipped[shipped["target"] == target].reset_index(drop=True)
        assert (part["seeds"] >= 2).all() and part["point"].nunique() == 48
        law = fit_law(part)
        coef = published["targets"][target]["law"]["coef"]
        np.testing.assert_allclose([coef[t] for t in LAW], law.coef, rtol=1e-6)
        block = published["config"]["noise_model"][target]
        assert block == {"rel_sd": round(math.exp(law.coef[0]), 5), "n_exponent": round(law.coef[1], 4),
                         "h_over_d_exponent": round(law.coef[2], 4)}


def test_the_shipped_config_sets_the_published_law_and_the_published_configs_keep_their_bands():
    """config.yaml's noise_model is the law of its scene: the adhesive default takes docs/noise/adhesive's
    refit, and its comment gives docs/noise's dry law, word for word, for a dry config; the published
    studies' configs have none, so their cases' SDs are the stated ones x the bands they ran with."""
    from spreadmap import config as spreadmap_config

    shipped = spreadmap_config.load(ROOT / "config.yaml")
    assert shipped["material"]["surface_energy_j_m2"] > 0
    adhesive = json.loads((ROOT / "docs" / "noise" / "adhesive" / "law.json").read_text())["config"]["noise_model"]
    assert shipped["noise_model"] == adhesive
    dry = json.loads((ROOT / "docs" / "noise" / "law.json").read_text())["config"]["noise_model"]
    text = (ROOT / "config.yaml").read_text()
    for target in ("mfr", "pd"):
        law = dry[target]
        assert (f"#     {target}: {{rel_sd: {law['rel_sd']}, n_exponent: {law['n_exponent']}, "
                f"h_over_d_exponent: {law['h_over_d_exponent']}}}") in text
    assert all(set(region["targets"]).isdisjoint({"mfr", "pd"}) for region in shipped["noise_calibration"])
    study = spreadmap_config.load(ROOT / "docs" / "study" / "config.yaml")
    assert "noise_model" not in study
    table = results_table()
    pd.testing.assert_frame_equal(case_noise(table, study.get("noise_model"), study["noise_calibration"]),
                                  calibrated_noise(table, study["noise_calibration"]))
