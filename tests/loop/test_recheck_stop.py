"""tools/recheck_stop.py: the published loop's last step decided again under another noise
calibration, with today's map model. Checked against the step the loop itself recorded, and the noise it is held against
recomputed here from the cases table with numpy (h/d masks written out, not calibrated_noise).
spreadlab.recheck: every step of a published main-job run decided again with another noise law."""
import json

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT, script_module

STUDY = ROOT / "docs" / "study"
recheck_stop = script_module("tools/recheck_stop.py")


def test_the_published_stop_holds_under_the_studys_calibration_and_matches_the_loops_own_step():
    from spreadmap import config as spreadmap_config

    cfg = spreadmap_config.load(STUDY / "config.yaml")
    table = pd.read_csv(STUDY / "cases_converge.csv")
    previous, last = recheck_stop.last_two_steps(STUDY / "converge" / "steps")
    assert (previous["n"], last["n"], last["stop"]) == (288, 304, True)
    # the hand bands the study ran with (config.yaml's MFR and PD noise is now the fitted law, docs/noise)
    record = recheck_stop.recheck(table, cfg, last, previous, cfg["noise_calibration"])
    assert record["stop"] and record["n"] == 304
    cv = record["criteria"]["at_this_batch"]["cv_rmse"]["targets"]
    own = last["criteria"]["at_this_batch"]["cv_rmse"]["targets"]
    lds = table[np.asarray(last["is_lds"], bool)]
    h_over_d = lds["h_um"] / lds["d_um"]
    factor = np.where(h_over_d < 2.0, 1.37, np.where(h_over_d >= 3.0, 0.61, 1.0))
    for target in ("mfr", "pd"):
        noise = np.sqrt(np.mean((lds[f"{target}_sd"] * factor) ** 2))
        assert abs(cv[target]["noise_sd"] - noise) < 1e-9
        assert abs(cv[target]["threshold"] - 1.2 * noise) < 1e-9
        # decided anew with the map's model (the loop then used a stand-in GP on raw inputs): its
        # CV RMSE is no worse than the stand-in's own (MFR 0.0133 against 0.0152 when written)
        assert cv[target]["rmse"] <= 1.02 * own[target]["rmse"]
        assert cv[target]["ratio"] < 1.0
    lines = recheck_stop.cv_lines("study", record)
    assert lines[0].startswith("study: stops") and "x the threshold" in lines[1]


def test_a_file_without_a_calibration_is_refused(tmp_path, capsys):
    bad = tmp_path / "other.yaml"
    bad.write_text(json.dumps({"preset": "default"}))
    assert recheck_stop.main(["--calibration", str(bad)]) == 2
    assert "no noise_calibration key (nor a noise_model)" in capsys.readouterr().err


@pytest.mark.slow
def test_a_runs_steps_decided_again_with_its_own_noise_law_reproduce_its_path():
    """spreadlab.recheck on the adhesive main job (docs/main_job/run_2026-12-06): its first two
    steps decided again with the law it ran with give its published map errors (2.57, 1.77) and its
    next batch, to the bit; with a law twice as noisy, the CV error net of noise falls."""
    from spreadlab.recheck import path_rows, recheck_path, run_steps
    from spreadmap import config as spreadmap_config

    run = ROOT / "docs" / "main_job" / "run_2026-12-06"
    steps = run_steps(run)[:2]
    table = pd.read_csv(run / "cases.csv")
    cfg = spreadmap_config.load(ROOT / "config.yaml")
    # the stop rule and batches as the run ran them (config.yaml's now: margin 1.0, batches of 8, stops
    # from 56 cases; docs/replay/adhesive)
    cfg["converge"]["map_error"]["margin"], cfg["converge"]["min_stop_cases"] = 1.7, 0
    cfg["converge"]["batch"] = 16
    # and the scene's window as it ran (3 d, the pile holding it): the planned cost of a candidate reads it
    cfg["presets"]["default"].update(transient_d=3, pile_transient_d=None)
    law = steps[0]["noise_model"]
    again = recheck_path(table, cfg, steps, law)
    for mine, published in zip(again, steps):
        assert mine["n"] == published["n"] and mine["next_batch"] == published["next_batch"]
        assert mine["criteria"]["at_this_batch"]["map_error"]["value"] == pytest.approx(
            published["criteria"]["at_this_batch"]["map_error"]["value"], rel=1e-9)
    assert [round(r["map_error_ratio"], 2) for r in path_rows(again, "dry")] == [2.57, 1.77]
    noisier = {**law, **{t: {**law[t], "rel_sd": 2 * law[t]["rel_sd"]} for t in ("mfr", "pd")}}
    first = path_rows(recheck_path(table, cfg, steps[:1], noisier), "x2")[0]
    assert first["mfr_cv_noise_sd"] == pytest.approx(2 * path_rows(again, "dry")[0]["mfr_cv_noise_sd"], rel=1e-9)
    assert first["mfr_cv_net_of_noise"] < path_rows(again, "dry")[0]["mfr_cv_net_of_noise"]
