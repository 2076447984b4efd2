"""The targets' one home, spreadmap.targets: the schema's lists of target names match it, and a
target registered there alone reaches a case's row of the table, the surrogate's targets and a
map's data."""
import importlib.util

import numpy as np
import pytest
import synthetic_cases as syn
import yaml
from conftest import ROOT

from spreadmap import targets
from spreadmap.maps import grids, machine
from spreadmap.metrics import case as case_metrics_module
from spreadmap.surrogate import fitting
from spreadmap.surrogate.settings import resolve_targets

SCHEMA = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())["properties"]
QUICK = {"cv_repeats": 1, "gp_restarts": 0, "learning_curve": False, "mlp_sizes": [4], "mlp_alphas": [1.0],
         "ensemble_members": 4, "neurons": [2], "seeds": [0], "model": "gp"}


def _metrics_helpers():
    """tests/metrics/test_metrics.py's hand-built raw record and its rules, bounds and settings."""
    spec = importlib.util.spec_from_file_location("_metric_cases", ROOT / "tests" / "metrics" / "test_metrics.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_schema_lists_the_registered_targets():
    """Where the schema lists target names, it lists the registry's (in its order): the noise
    calibration's targets, the fidelity correction's factors; the noise law covers the targets with
    a count; the loop's map tolerance names the base targets."""
    assert SCHEMA["noise_calibration"]["items"]["properties"]["targets"]["items"]["enum"] == list(targets.names())
    assert list(SCHEMA["fidelity_correction"]["properties"]["targets"]["properties"]) == list(targets.names())
    counted = [t.name for t in targets.REGISTRY.values() if t.count_column]
    assert SCHEMA["noise_model"]["required"] == counted
    assert [k for k in SCHEMA["noise_model"]["properties"] if k in targets.REGISTRY] == counted
    tolerance = SCHEMA["converge"]["properties"]["map_error"]["properties"]["tolerance"]["properties"]
    assert list(tolerance) == list(targets.names("base"))


def test_registry_fields_and_refusals():
    assert targets.names("base") == ("mfr", "pd")
    assert targets.axis_label("mfr") == "mass flow rate MFR [-]" and targets.short("roughness_d") == "roughness/d"
    assert targets.axis_label("not_a_target") == "not_a_target" and targets.definition("pd") is None
    assert targets.get("layer_fill").definition.startswith("layer fill")
    with pytest.raises(ValueError, match="no target 'x'.*registered"):
        targets.get("x")
    with pytest.raises(ValueError, match="kind 'bulk'"):
        targets.Target("x", "x", "x", "-", "x_sd", None, "bulk", "x")


TOY = targets.Target("toy", "toy measure", "toy", "-", "toy_sd", None, "layer", "toy measure")


def test_a_toy_target_registered_once_reaches_the_table_the_surrogate_and_a_map(monkeypatch):
    """Registered in spreadmap.targets (and computed by the metric's own code, here a wrapper of
    metrics.case.measure), the toy target is a column of a case's row, a target the surrogate
    models under `targets: auto`, a candidate of the machine map's y axis and a column of its data."""
    monkeypatch.setitem(targets.REGISTRY, "toy", TOY)
    m = _metrics_helpers()
    real_measure = case_metrics_module.measure

    def measure_with_toy(raw, settings):  # the toy's metric: twice the coverage, its SD twice coverage's
        out = real_measure(raw, settings)
        return {**out, "toy": 2 * out["coverage"], "toy_sd": 2 * out["coverage_sd"]}

    monkeypatch.setattr(case_metrics_module, "measure", measure_with_toy)
    row = case_metrics_module.case_metrics(m.raw_record(layers=2), m.RULES, m.BOUNDS, m.SETTINGS)
    assert list(row)[-2:] == ["toy", "toy_sd"]
    assert row["toy"] == pytest.approx(2 * row["coverage"])

    cases = syn.table(40, 0.05, seed=4)
    cases["toy"] = 0.2 + 0.5 * cases["mfr"]
    cases["toy_sd"] = 0.5 * cases["mfr_sd"]
    assert resolve_targets("auto", cases.columns) == ["mfr", "pd", "toy"]
    model = fitting.fit_surrogate(cases, QUICK, log=lambda *a: None).model
    assert "toy" in model.targets
    y, scores = grids.choose_machine_y(cases, model.targets)
    assert "toy" in set(scores["target"])
    grid = machine.machine_grid(model, y="toy", n_h=4, n_v=3)
    assert {"toy", "toy_model_sd", "toy_run_sd"} <= set(grid.columns)
    assert np.isfinite(grid["toy"]).all()
