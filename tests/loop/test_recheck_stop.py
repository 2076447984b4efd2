"""tools/recheck_stop.py: the published loop's last step decided again under another noise
calibration, with today's map model. Checked against the step the loop itself recorded, and the noise it is held against
recomputed here from the cases table with numpy (h/d masks written out, not calibrated_noise)."""
import json

import numpy as np
import pandas as pd
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
