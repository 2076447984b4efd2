"""The preset-to-reference correction of the map model (spreadmap.surrogate.correction): the product's
moments against Monte Carlo draws, the saved model's predictions and draws, the config's errors. No YADE."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import synthetic_cases as syn
from conftest import ROOT

from spreadmap.surrogate import fitting, saved_model
from spreadmap.surrogate.correction import Correction, uncorrected_label

QUICK = {"cv_repeats": 1, "cv_folds": 3, "gp_restarts": 0, "learning_curve": False, "mlp_sizes": [4], "mlp_alphas": [1.0],
         "ensemble_members": 4, "neurons": [2], "seeds": [0]}
SECTION = {"preset": "default", "reference": "reference",
           "targets": {"mfr": {"factor": 1.04, "sd": 0.012}, "pd": {"factor": 1.02, "sd": 0.01}}}


@pytest.fixture(scope="module")
def model():
    return fitting.fit_surrogate(syn.table(40, 0.03, seed=2), QUICK, log=lambda *a: None).model


def test_stats_are_the_moments_of_the_product_of_independent_normals():
    corr = Correction.from_config({"fidelity_correction": SECTION})
    mean, msd, rsd = np.array([0.3, 0.5]), np.array([0.01, 0.03]), np.array([0.02, 0.04])
    m2, s2, r2 = corr.stats("mfr", mean, msd, rsd)
    rng = np.random.default_rng(0)
    n = 1_000_000
    k = rng.normal(1.04, 0.012, n)
    for i in range(2):
        product = rng.normal(mean[i], msd[i], n) * k
        assert m2[i] == pytest.approx(product.mean(), rel=2e-3)
        assert s2[i] == pytest.approx(product.std(), rel=5e-3)
    assert r2[1] == pytest.approx(np.sqrt(1.04**2 * 0.04**2 + (0.5**2 + 0.04**2) * 0.012**2))
    # a target without a factor is left as it is
    assert corr.stats("coverage", mean, msd, rsd)[0] is mean


def test_saved_model_reads_through_the_correction(model):
    corr = Correction.from_config({"fidelity_correction": SECTION})
    fixed = dataclasses.replace(model, correction=corr)
    X = np.array([[0.3, 30.0, 65.0, 10.0], [0.2, 45.0, 57.0, 6.0], [0.4, 15.0, 70.0, 14.0]])
    plain, got = model.predict_stats(X), fixed.predict_stats(X)
    assert got["mfr"][0] == pytest.approx(1.04 * plain["mfr"][0])
    assert got["pd"][0] == pytest.approx(1.02 * plain["pd"][0])
    assert (got["mfr"][1] > 1.04 * plain["mfr"][1]).all()
    assert fixed(X)[:, 0] == pytest.approx(1.04 * model(X)[:, 0])
    # draws: the factor is one number per draw, so it moves every point of a map together
    d_plain, d_fixed = model.draws(X, 4000, seed=1)["mfr"], fixed.draws(X, 4000, seed=1)["mfr"]
    assert d_fixed.mean(axis=0) == pytest.approx(1.04 * d_plain.mean(axis=0), rel=5e-3)
    ratio = d_fixed / d_plain[:, :]  # the same posterior draws (same seed), times one k per row
    assert np.allclose(ratio, ratio[:, :1])
    assert ratio[:, 0].std() == pytest.approx(0.012, rel=0.06)


def test_saved_and_loaded_model_keeps_its_correction(model, tmp_path):
    corr = Correction.from_config({"fidelity_correction": SECTION})
    path = tmp_path / "m.joblib"
    saved_model.save_model(dataclasses.replace(model, correction=corr), path)
    back = saved_model.load_model(path)
    assert back.correction == corr
    X = np.array([[0.3, 30.0, 65.0, 10.0]])
    assert back.predict_stats(X)["mfr"][0] == pytest.approx(1.04 * model.predict_stats(X)["mfr"][0])


def test_config_and_labels():
    assert Correction.from_config({}) is None and Correction.from_config({"fidelity_correction": None}) is None
    corr = Correction.from_config({"fidelity_correction": SECTION})
    assert corr.label(("mfr", "pd", "coverage")) == ("`default` corrected to `reference`: MFR x1.040 (SD 0.012), "
                                                    "PD x1.020 (SD 0.010); coverage as `default` reads")
    with pytest.raises(ValueError, match="fidelity_correction.targets.mfr"):
        Correction.from_config({"fidelity_correction": {"targets": {"mfr": {"factor": -1, "sd": 0.1}}}})
    assert uncorrected_label("default") == "`default` preset, not corrected to `reference`"


def test_maps_support_is_the_models_own_not_the_factors(model):
    """A factor widens every SD (here far beyond one run's noise) but is no lack of data: the maps'
    support (spreadmap.maps.grids.evaluate) reads the model's own SD, so it is the same either way,
    while the drawn SDs carry the factor's error."""
    from spreadmap.maps import grids

    wide = Correction.from_config({"fidelity_correction": {"targets": {"mfr": {"factor": 1.05, "sd": 0.2}}}})
    fixed = dataclasses.replace(model, correction=wide)
    frame = grids.grid_frame(f=[0.3], d_um=[20.0, 35.0, 50.0], h_um=[55.0, 65.0, 75.0], v_mm_s=[10.0])
    support = {"max_distance": 1.5, "max_sd_ratio": 1.0}
    plain, got = grids.evaluate(model, frame, ["mfr"], support), grids.evaluate(fixed, frame, ["mfr"], support)
    assert got["supported"].tolist() == plain["supported"].tolist() and plain["supported"].any()
    assert got["mfr_sd_ratio"].to_numpy() == pytest.approx(plain["mfr_sd_ratio"].to_numpy())
    m, s = plain["mfr"].to_numpy(), plain["mfr_model_sd"].to_numpy()
    assert got["mfr_model_sd"].to_numpy() == pytest.approx(np.sqrt(1.05**2 * s**2 + (m**2 + s**2) * 0.2**2))
    assert (got["mfr_model_sd"] > got["mfr_noise_sd"]).any()  # wider than one run's noise, still supported


def test_a_factor_of_another_floor_or_preset_does_not_apply():
    """The shipped factor is for `default` on the rough floor: a run on the flat floor or at another
    preset reads as its preset does, and its maps say why."""
    from spreadmap import config as spreadmap_config
    from spreadmap.surrogate.correction import applies

    cfg = spreadmap_config.load(ROOT / "config.yaml")
    assert cfg["fidelity_correction"]["floor"] == cfg["scene"]["substrate"]["kind"] == "rough"
    # measured on dry spheres: the adhesive default does not take it, and its maps say why
    assert cfg["material"]["surface_energy_j_m2"] == 1e-4
    assert Correction.from_config(cfg) is None
    assert applies(cfg) == "its factors were measured with surface energy 0 mJ/m^2, the run's is 0.1 mJ/m^2"
    cfg["material"]["surface_energy_j_m2"] = 0.0
    assert Correction.from_config(cfg) is not None and applies(cfg) is None
    cfg["scene"]["substrate"]["kind"] = "flat"
    spreadmap_config.validate(cfg)
    assert Correction.from_config(cfg) is None and applies(cfg) == "its factors were measured on the rough floor"
    cfg["scene"]["substrate"]["kind"] = "rough"
    cfg["preset"] = "fast"
    assert Correction.from_config(cfg) is None
    assert uncorrected_label("fast", why=applies(cfg)) == ("`fast` preset, not corrected to `reference` "
                                                          "(its factors are for `default`)")
