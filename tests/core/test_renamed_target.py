"""The layer fill's column is `layer_fill` (issue 52; it was `layer_packing`): the table the workflow
writes names it so, and what was written under the old name reads under the new one: a published
cases table (and analyses), a metrics record of an earlier run, a config that lists it, the
held-out tool given it."""
import json
import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest
import yaml
from conftest import ROOT
from test_targets import _metrics_helpers

from spreadmap import config as spreadmap_config
from spreadmap import targets
from spreadmap.metrics import case_metrics
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import current_columns, read_table
from spreadmap.surrogate.settings import resolve_targets
from spreadmap.table import build_table, write_table

OLD_TABLE = ROOT / "docs" / "main_job" / "run_2026-12-06" / "cases.csv"  # published before the rename
OLD_CONFIG = ROOT / "docs" / "fidelity" / "correction" / "config.yaml"  # lists layer_packing


def test_the_name_now_of_a_column():
    assert targets.current_name("layer_packing") == "layer_fill"
    assert targets.current_name("layer_packing_sd") == "layer_fill_sd"
    assert targets.current_name("layer_packing_model_sd") == "layer_fill_model_sd"
    assert [targets.current_name(c) for c in ("layer_fill", "mfr", "coverage_sd", "layer_packings")] == \
        ["layer_fill", "mfr", "coverage_sd", "layer_packings"]
    assert "layer_fill" in targets.names("layer") and "layer_packing" not in targets.REGISTRY


def test_a_published_table_under_the_old_name_reads_and_analyses_as_a_new_one():
    raw = pd.read_csv(OLD_TABLE)
    assert {"layer_packing", "layer_packing_sd"} <= set(raw.columns)  # the file as published
    table = read_table(OLD_TABLE)
    assert "layer_packing" not in table.columns and "layer_packing_sd" not in table.columns
    np.testing.assert_array_equal(table["layer_fill"], raw["layer_packing"])
    np.testing.assert_array_equal(table["layer_fill_sd"], raw["layer_packing_sd"])
    assert list(table.columns) == [targets.current_name(c) for c in raw.columns]  # in their place
    assert "layer_fill" in resolve_targets("auto", table.columns)  # the surrogate models it
    # the shipped calibration scales the layer fill's SD by 1.37 below h/d 2, as it did the old column's
    calibration = [{"h_over_d_below": 2.0, "factor": 1.37, "targets": ["layer_fill"]}]
    noisy = case_noise(table, None, calibration, 0.45)
    thin = (raw["h_um"] / raw["d_um"] < 2.0).to_numpy()
    assert 0 < thin.sum() < len(raw)
    np.testing.assert_allclose(noisy["layer_fill_sd"][thin], 1.37 * raw["layer_packing_sd"][thin], rtol=1e-12)
    np.testing.assert_allclose(noisy["layer_fill_sd"][~thin], raw["layer_packing_sd"][~thin], rtol=1e-12)


def test_records_of_both_ages_make_one_column():
    """A results folder holding metrics records from before the rename and after it: one column."""
    old = pd.DataFrame({"case_id": ["a", "b"], "layer_packing": [0.81, 0.79], "layer_packing_sd": [0.01, 0.02]})
    new = pd.DataFrame({"case_id": ["c"], "layer_fill": [0.77], "layer_fill_sd": [0.03]})
    both = current_columns(pd.concat([old, new], ignore_index=True))
    assert list(both.columns) == ["case_id", "layer_fill", "layer_fill_sd"]
    assert list(both["layer_fill"]) == [0.81, 0.79, 0.77] and list(both["layer_fill_sd"]) == [0.01, 0.02, 0.03]
    assert current_columns(new) is new  # nothing old: the table itself


def test_the_table_the_workflow_writes_has_layer_fill(tmp_path):
    """A case's metrics (metrics.case.case_metrics of a hand-built raw record) name the layer fill
    `layer_fill`; so does the results table built from them; a record from an earlier run (the same
    values under `layer_packing`) joins the same column."""
    m = _metrics_helpers()
    row = case_metrics(m.raw_record(layers=2), m.RULES, m.BOUNDS, m.SETTINGS)
    assert "layer_fill" in row and "layer_packing" not in row
    assert row["layer_fill"] == pytest.approx(8 / 11, rel=2e-3)  # two square layers (tests/metrics/test_layer.py)
    new = {**row, "case_id": "new"}
    old = {k.replace("layer_fill", "layer_packing"): v for k, v in row.items()}
    old["case_id"] = "old"
    for name, record in (("new", new), ("old", old)):
        (tmp_path / f"{name}.json").write_text(json.dumps(record))
    table = build_table([tmp_path / "new.json", tmp_path / "old.json"], [tmp_path / "none.tsv"] * 2,
                        [{"sweep": "lds", "index": i} for i in range(2)])
    write_table(table, tmp_path / "table.csv")
    header = (tmp_path / "table.csv").read_text().splitlines()[0].split(",")
    assert "layer_fill" in header and "layer_fill_sd" in header
    assert not [c for c in header if c.startswith("layer_packing")]
    written = pd.read_csv(tmp_path / "table.csv")
    assert list(written["layer_fill"]) == pytest.approx([row["layer_fill"]] * 2)


def test_a_config_listing_the_old_name_validates_with_a_warning():
    with pytest.warns(FutureWarning, match=r"'layer_packing' \(now 'layer_fill'\) in noise_calibration\[0\]\.targets"):
        cfg = spreadmap_config.load(OLD_CONFIG)
    assert cfg["noise_calibration"][0]["targets"] == ["layer_fill", "coverage", "roughness_d", "thickness_ratio"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", FutureWarning)
        shipped = spreadmap_config.load(ROOT / "config.yaml")  # the shipped config: the new name, no warning
    assert "layer_fill" in shipped["noise_calibration"][0]["targets"]


def test_the_old_name_as_a_key_and_as_one_name_and_both_names_refused():
    base = yaml.safe_load((ROOT / "config.yaml").read_text())
    cfg = {**base, "decisions": {**base.get("decisions", {}), "bounds": {"layer_packing": {"min": 0.6}},
                                 "quality": {"target": "layer_packing"}},
           "surrogate": {**base["surrogate"], "targets": ["mfr", "pd", "layer_packing"]}}
    with pytest.warns(FutureWarning, match=r"decisions\.bounds, decisions\.quality\.target"):
        got = spreadmap_config.validate(cfg)
    assert got["decisions"]["bounds"] == {"layer_fill": {"min": 0.6}}
    assert got["decisions"]["quality"]["target"] == "layer_fill"
    assert got["surrogate"]["targets"] == ["mfr", "pd", "layer_fill"]
    both = {**base, "decisions": {**base.get("decisions", {}),
                                  "bounds": {"layer_packing": {"min": 0.6}, "layer_fill": {"min": 0.7}}}}
    with pytest.raises(spreadmap_config.ConfigError, match="decisions.bounds' has both 'layer_packing' and 'layer_fill'"):
        spreadmap_config.validate(both)


def test_the_heldout_tool_scores_an_old_named_target_of_published_files(tmp_path):
    """tools/heldout.py score on the study's published held-out files (made under the old name)
    with --targets layer_packing: the layer fill's published score, now under its new name."""
    folder = ROOT / "docs" / "study" / "heldout"
    out = tmp_path / "score.csv"
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "heldout.py"), "score", "--points",
                        str(folder / "points.csv"), "--predictions", str(folder / "predictions.csv"), "--table",
                        str(ROOT / "docs" / "study" / "cases_heldout.csv"), "--targets", "layer_packing",
                        "--out", str(out)], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    got = json.loads(out.with_suffix(".json").read_text())
    published = {s["target"]: s for s in json.loads((folder / "score.json").read_text())}["layer_packing"]
    assert [s["target"] for s in got] == ["layer_fill"]
    assert {k: v for k, v in got[0].items() if k != "target"} == pytest.approx(
        {k: v for k, v in published.items() if k != "target"}, rel=1e-12)
