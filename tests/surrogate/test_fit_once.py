"""The surrogate in two rules (issue 50): rule surrogate fits the map model alone (``fit_map_model``)
and rule surrogate_validation validates it (``validate_surrogate``), so that the maps do not wait
for the validation. The model they save is the one the single rule saved (``fit_surrogate``, the
validation first, then the fit): the same predictions to 1e-12 on a published table. No YADE."""
from __future__ import annotations

import copy
import runpy
import sys
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT

from spreadmap.design import Design
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import read_table
from spreadmap.surrogate import fitting, saved_model
from spreadmap.surrogate.correction import Correction
from spreadmap.surrogate.settings import make_config

TABLE = ROOT / "docs" / "main_job" / "cases.csv"  # the published main job of 32 cases (6 targets)
# small but every part of the final fit: optimizer restarts, an MLP ensemble that picks its size and
# penalty inside the folds
QUICK = {"cv_folds": 4, "cv_repeats": 1, "gp_restarts": 1, "learning_curve": False, "mlp_sizes": [2, 4],
         "mlp_alphas": [0.1, 1.0], "ensemble_members": 3, "neurons": [2], "seeds": [0]}
SILENT = {"log": lambda *a: None}


@pytest.fixture(scope="module")
def table(config):
    return case_noise(read_table(TABLE), config.get("noise_model"), config["noise_calibration"],
                      config["metrics"]["counting_noise_c"])


@pytest.fixture(scope="module")
def design(config):
    return Design.from_ranges(config.get("ranges"))


@pytest.fixture(scope="module")
def single_rule(table, design):
    """The single rule's path: the validation, then the map model (fit_surrogate)."""
    return fitting.fit_surrogate(table, QUICK, source_path=TABLE, ranges=design, **SILENT)


def _points(model, n=64):
    rng = np.random.default_rng(11)
    inside = model.design_low + rng.random((n, 4)) * (model.design_high - model.design_low)
    return np.vstack([inside, model.train_X])  # anywhere in the box, and on the cases


def assert_same_model(new, old, tol=1e-12):
    """Same targets, model kinds and training cases, the same predictions (means, model SDs, run
    SDs, as read and as the preset reads) and posterior draws, to `tol`."""
    assert new.targets == old.targets and new.correction == old.correction
    assert {t: new.kind(t) for t in new.targets} == {t: old.kind(t) for t in old.targets}
    assert np.array_equal(new.train_X, old.train_X)
    X = _points(old)
    for corrected in (True, False):
        a, b = new.predict_stats(X, corrected=corrected), old.predict_stats(X, corrected=corrected)
        for t in old.targets:
            for x, y in zip(a[t], b[t]):
                assert np.max(np.abs(np.asarray(x) - np.asarray(y))) <= tol, (t, corrected)
    da, db = new.draws(X, 8, seed=3), old.draws(X, 8, seed=3)
    for t in old.targets:
        assert np.max(np.abs(da[t] - db[t])) <= tol, t


def _metadata(model, drop=("validation", "study", "notes", "versions")):
    return {k: v for k, v in model.metadata.items() if k not in drop}


def test_the_map_model_alone_is_the_single_rules_model(table, design, single_rule):
    old = single_rule.model
    new = fitting.fit_map_model(table, QUICK, source_path=TABLE, ranges=design, **SILENT)
    assert len(new.targets) == 6 and {new.kind(t) for t in new.targets} == {"gp"}
    assert_same_model(new, old)
    assert _metadata(new) == _metadata(old)  # the cases, their hash, the study's split sizes, ...
    assert "validation" not in new.metadata and "validation" in old.metadata
    # the validation's rows and choice are the model's
    assert single_rule.rows.X.tolist() == new.train_X.tolist()
    assert new.metadata["map_model"] == {t: "gp" for t in new.targets}
    assert new.metadata["n_train"] == int(single_rule.study_runs["n_train"].iloc[0])
    assert new.metadata["n_test"] == int(single_rule.study_runs["n_test"].iloc[0])


def test_the_mlp_map_model_alone_is_the_single_rules_model(table):
    """The bootstrap MLP ensemble (its size and penalty chosen inside its own folds) too."""
    cfg = {**QUICK, "model": "mlp", "targets": ["mfr", "pd"]}
    old = fitting.fit_surrogate(table, cfg, **SILENT).model
    new = fitting.fit_map_model(table, cfg, **SILENT)
    assert {new.kind(t) for t in new.targets} == {"mlp"}
    assert_same_model(new, old)


def test_the_scripts_save_the_model_the_single_rule_saved(config, single_rule, tmp_path, monkeypatch):
    """scripts/surrogate.py (the model, with the fidelity correction) and scripts/surrogate_validation.py
    (the numbers and the figures) against the single rule's path: fit_surrogate, the correction
    attached, save_model."""
    section = config["fidelity_correction"]
    noise = dict(noise_calibration=config["noise_calibration"], noise_model=config.get("noise_model"),
                 counting_c=config["metrics"]["counting_noise_c"])
    out = tmp_path / "surrogate"
    monkeypatch.setattr(sys, "stdout", sys.stdout)  # the scripts tee them into their logs: restored after
    monkeypatch.setattr(sys, "stderr", sys.stderr)
    model_rule = SimpleNamespace(
        input=SimpleNamespace(table=str(TABLE)), log=[str(tmp_path / "surrogate.log")],
        output=SimpleNamespace(model=str(out / "model.joblib"), metadata=str(out / "model.json")),
        params=SimpleNamespace(surrogate=QUICK, ranges=config.get("ranges"), correction=section, **noise))
    runpy.run_path(str(ROOT / "scripts" / "surrogate.py"), init_globals={"snakemake": model_rule}, run_name="__main__")
    validation_rule = SimpleNamespace(  # the figures: named by the script's prefix, beside the metrics
        input=SimpleNamespace(table=str(TABLE)), log=[str(tmp_path / "surrogate_validation.log")],
        output=SimpleNamespace(metrics=str(out / "surrogate_metrics.csv"),
                               study_runs=str(out / "surrogate_study_runs.csv")),
        params=SimpleNamespace(surrogate=QUICK, floor="flat floor; dry", **noise), threads=1)
    runpy.run_path(str(ROOT / "scripts" / "surrogate_validation.py"), init_globals={"snakemake": validation_rule},
                   run_name="__main__")

    old = copy.deepcopy(single_rule)
    correction = Correction.from_config({"fidelity_correction": section})
    assert correction is not None
    old.model.correction = correction  # as the single rule's script attached it
    old.model.metadata["fidelity_correction"] = {"label": correction.label(old.model.targets),
                                                 "factors": correction.factors, "source": correction.source}
    saved_model.save_model(old.model, tmp_path / "old" / "model.joblib")
    new = saved_model.load_model(out / "model.joblib")
    assert_same_model(new, saved_model.load_model(tmp_path / "old" / "model.joblib"))
    assert _metadata(new) == _metadata(old.model)
    assert new.metadata["fidelity_correction"]["factors"] == correction.factors and correction.factors["mfr"][0] != 1

    # the validation's numbers are the single rule's
    pd.testing.assert_frame_equal(pd.read_csv(out / "surrogate_metrics.csv"),
                                  pd.read_csv(pd.io.common.StringIO(old.validation.to_csv(index=False))))
    pd.testing.assert_frame_equal(pd.read_csv(out / "surrogate_study_runs.csv"),
                                  pd.read_csv(pd.io.common.StringIO(old.study_runs.to_csv(index=False))))
    for name in ("parity", "r2_vs_neurons", "learning_curve"):
        for ext in ("png", "pdf", "csv"):
            assert (out / f"surrogate_{name}.{ext}").stat().st_size > 0, (name, ext)


def test_best_takes_the_validations_choice(table, tmp_path):
    """`model: best`: the validation chooses each target's model, so the map model reads the
    validation's table (the rule asks for surrogate_metrics.csv) and is the single rule's model."""
    cfg = {**QUICK, "model": "best", "targets": ["mfr", "pd", "coverage"]}
    with pytest.raises(ValueError, match="'best' picks each target's model by its validation"):
        fitting.fit_map_model(table, cfg, **SILENT)
    old = fitting.fit_surrogate(table, cfg, **SILENT)  # validate_surrogate, then the model
    path = tmp_path / "surrogate_metrics.csv"
    old.validation.to_csv(path, index=False)  # as rule surrogate_validation writes it
    new = fitting.fit_map_model(table, cfg, validation=pd.read_csv(path), **SILENT)
    assert new.metadata["map_model"] == old.model.metadata["map_model"]
    assert new.metadata["validation"] == old.model.metadata["validation"]  # the choice's numbers, recorded
    assert_same_model(new, old.model)
    # the model is the one the validation's table marks (here the GP wins every target: mark PD's MLP)
    flipped = pd.read_csv(path)
    flipped.loc[flipped["target"] == "pd", "map_model"] = flipped.loc[flipped["target"] == "pd", "model"] == "mlp"
    assert fitting.fit_map_model(table, cfg, validation=flipped, **SILENT).kind("pd") == "mlp"


def test_a_validation_of_another_config_or_table_is_refused(table):
    cfg = make_config({**QUICK, "model": "gp"})
    targets = ["mfr", "pd"]
    mlp = pd.DataFrame({"target": ["mfr", "mfr", "pd", "pd"], "model": ["gp", "mlp"] * 2,
                        "map_model": [False, True, False, True]})
    with pytest.raises(ValueError, match="a validation of another config"):
        fitting.chosen_models(cfg, targets, mlp)
    with pytest.raises(ValueError, match="marks 0 map models for target 'coverage'"):
        fitting.chosen_models(make_config({**QUICK, "model": "best"}), [*targets, "coverage"], mlp)
    assert fitting.chosen_models(make_config({**QUICK, "model": "best"}), targets, mlp) == {"mfr": "mlp",
                                                                                                   "pd": "mlp"}
    assert fitting.chosen_models(cfg, targets) == {"mfr": "gp", "pd": "gp"}


def test_the_validation_in_two_processes_is_the_validation_in_one(table, single_rule):
    """The rule runs the k-fold validations a process per core (joblib); the tables are the single
    process's (the single rule's path ran with n_jobs 1), to the bit."""
    two = fitting.validate_surrogate(table, QUICK, n_jobs=2, **SILENT)
    pd.testing.assert_frame_equal(two.validation, single_rule.validation, check_exact=True)
    pd.testing.assert_frame_equal(two.oof, single_rule.oof, check_exact=True)
