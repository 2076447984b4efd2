"""The fidelity study published in docs/fidelity/ (the README's numbers) is the study its own
config (docs/fidelity/config.yaml, the configuration it ran with: the study's flat floor and fixed
window, before the precision scene) plans, and its tables are what the package computes from its
published cases."""
import copy

import numpy as np
import pandas as pd
import pytest

from conftest import ROOT
from spreadmap import config as spreadmap_config
from spreadmap import fidelity_plan as plan
from spreadmap import fidelity_study as study
from spreadmap.cases import case_id

DOCS = ROOT / "docs" / "fidelity"


@pytest.fixture(scope="module")
def shipped():
    cfg = spreadmap_config.load(DOCS / "config.yaml")
    cfg["presets"].update(plan.knob_presets(copy.deepcopy(cfg)))
    return cfg


def test_published_cases_are_the_planned_cases(shipped):
    cases = pd.read_csv(DOCS / "cases_presets.csv")
    planned = [case_id(r["point"], r["preset"], r["seed"]) for r in plan.preset_cases(shipped)]
    assert list(cases["case_id"]) == planned
    knobs = pd.read_csv(DOCS / "cases_knobs.csv")
    assert list(knobs["case_id"]) == [case_id(r["point"], r["preset"], r["seed"]) for r in plan.knob_cases(shipped)]
    assert (cases["status"] == "ok").all() and (knobs["status"] == "ok").all()
    assert cases["cpu_time"].notna().all() and knobs["cpu_time"].notna().all()


def _same(published: pd.DataFrame, computed: pd.DataFrame):
    assert list(published.columns) == list(computed.columns)
    for column in computed.columns:
        if pd.api.types.is_numeric_dtype(computed[column]) and not pd.api.types.is_bool_dtype(computed[column]):
            np.testing.assert_allclose(published[column].to_numpy(dtype=float), computed[column].to_numpy(dtype=float),
                                       rtol=1e-9, equal_nan=True, err_msg=column)
        else:
            assert published[column].astype(str).tolist() == computed[column].astype(str).tolist(), column


def test_published_tables_are_recomputed_from_the_published_cases(shipped):
    per_point, presets = study.preset_errors(pd.read_csv(DOCS / "cases_presets.csv"), shipped["fidelity"]["reference"])
    _same(pd.read_csv(DOCS / "presets.csv"), presets)
    _same(pd.read_csv(DOCS / "per_point.csv"), per_point)
    _same(pd.read_csv(DOCS / "knobs.csv"), study.knob_errors(pd.read_csv(DOCS / "cases_knobs.csv")))
