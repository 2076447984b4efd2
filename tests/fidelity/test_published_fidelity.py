"""Each published fidelity study (docs/fidelity/: the default scene; docs/fidelity_flat/: the
study's flat floor and fixed window, before the precision scene) is the study its own config (its
config.yaml, the configuration it ran with) plans, and its tables are what the package computes
from its published cases."""
import copy

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT

from spreadmap import config as spreadmap_config
from spreadmap.case.identity import readable_id
from spreadmap.fidelity import plan, study

STUDIES = [d for d in (ROOT / "docs" / "fidelity", ROOT / "docs" / "fidelity_flat") if (d / "config.yaml").exists()]


@pytest.fixture(scope="module", params=STUDIES, ids=[d.name for d in STUDIES])
def published(request):
    cfg = spreadmap_config.load(request.param / "config.yaml")
    cfg["presets"].update(plan.knob_presets(copy.deepcopy(cfg)))
    return request.param, cfg


def test_published_cases_are_the_planned_cases(published):
    DOCS, shipped = published
    cases = pd.read_csv(DOCS / "cases_presets.csv")
    # published before content keys (issue 35): the ids are the readable part alone
    planned = [readable_id(r["point"], r["preset"], r["seed"]) for r in plan.preset_cases(shipped)]
    assert list(cases["case_id"]) == planned
    knobs = pd.read_csv(DOCS / "cases_knobs.csv")
    assert list(knobs["case_id"]) == [readable_id(r["point"], r["preset"], r["seed"]) for r in plan.knob_cases(shipped)]
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


def test_published_tables_are_recomputed_from_the_published_cases(published):
    DOCS, shipped = published
    per_point, presets = study.preset_errors(pd.read_csv(DOCS / "cases_presets.csv"), shipped["fidelity"]["reference"])
    _same(pd.read_csv(DOCS / "presets.csv"), presets)
    _same(pd.read_csv(DOCS / "per_point.csv"), per_point)
    _same(pd.read_csv(DOCS / "knobs.csv"), study.knob_errors(pd.read_csv(DOCS / "cases_knobs.csv")))
