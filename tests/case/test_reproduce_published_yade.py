"""A case published before adhesion (issue 49), re-run on today's scene with surface energy 0: its
MFR and PD to the bit. The scene's template changed (adhesion, the monitor's overlap scan gone), so
its id did; what it simulates did not (with the window of then: the steady window of 2026-12-07 moved
it). Runs the real YADE binary (~20 s)."""
import copy

import pandas as pd
import pytest
from conftest import ROOT, case_params, run_scene

from spreadmap.metrics.case import case_metrics

pytestmark = pytest.mark.yade
PUBLISHED = ROOT / "docs" / "main_job" / "run_2026-12-04" / "cases.csv"


def test_surface_energy_0_reproduces_a_published_case_to_the_bit(tmp_path, config):
    row = pd.read_csv(PUBLISHED).set_index("index").loc[1]  # d 42.7 um, 17 s of CPU then
    cfg = copy.deepcopy(config)
    cfg["material"]["surface_energy_j_m2"] = 0.0
    # the window as it was then (3 d beyond the pile, the pile holding it; 5 d on a 3 d pile since 2026-12-07);
    # the overlap's read stride is today's: it only reads
    cfg["presets"]["default"].update(transient_d=3, pile_transient_d=None)
    point = {k: float(row[k]) for k in ("f", "d_um", "h_um", "v_mm_s")}
    params = case_params(cfg, point, row["preset"], seed=int(row["seed"]))
    assert params["adhesion_gamma"] == 0.0
    result, raw = run_scene(params, tmp_path)
    assert result["outcome"] == "ok", result
    out = case_metrics(raw, cfg["regime"], cfg["stability"], cfg["metrics"])
    print(f"MFR {out['mfr']!r} (published {row['mfr']!r}), PD {out['pd']!r} (published {row['pd']!r})")
    assert out["mfr"] == row["mfr"]
    assert out["pd"] == row["pd"]
    assert out["n_particles"] == row["n_particles"] and out["steps"] == row["steps"]
