"""Tests of spreadlab.experiments.replay's stop and honesty rules on constructed paths (the replay run
against a known truth is in tests/loop/test_convergence.py, beside the loop it drives)."""
import pandas as pd
import pytest


def test_replay_stops_and_honesty_on_a_constructed_path():
    """stops() takes the first step whose estimates are all within the tolerance (hold_for steps in
    a row); honesty() counts the stops within it and their Clopper-Pearson interval (checked with
    the beta quantiles)."""
    from scipy.stats import beta

    from spreadlab.experiments import replay

    rows = []
    for seed in range(10):
        for k, n in enumerate((32, 48, 64)):
            est = [0.03, 0.012, 0.008][k]
            true = [0.03, 0.011 if seed < 9 else 0.013, 0.008][k]
            rows.append({"design": "a", "seed": seed, "n": n, "cpu_h_modelled": n / 60,
                         "mfr_estimate": est, "pd_estimate": 0.005, "mfr_true": true, "pd_true": 0.005})
    paths = pd.DataFrame(rows)
    st = replay.stops(paths, {"mfr": 0.0125, "pd": 0.0125})
    assert (st["n"] == 48).all() and st["stopped"].all()
    assert st["true_within"].sum() == 9
    h = replay.honesty(st).iloc[0]
    assert h["honest_share"] == 0.9 and h["cases_median"] == 48
    assert h["honest_low"] == pytest.approx(beta.ppf(0.025, 9, 2)) and h["honest_high"] == pytest.approx(beta.ppf(0.975, 10, 1))
    assert (replay.stops(paths, {"mfr": 0.0125, "pd": 0.0125}, hold_for=2)["n"] == 64).all()
    never = replay.stops(paths, {"mfr": 0.001, "pd": 0.001})
    assert not never["stopped"].any() and replay.honesty(never).iloc[0]["stops"] == 0
    # a margin of 1.5 holds 0.018 against 0.0125 at 48 cases: the stops move to 64, all within
    assert (replay.stops(paths, {"mfr": 0.0125, "pd": 0.0125}, margin=1.5)["n"] == 64).all()
    # the smallest margin on the grid that makes 95 % of the stops honest: 1.05 (0.0126 > 0.0125)
    assert replay.calibrate_margin(paths, [0.0125], share=0.95) == 1.05
    assert replay.calibrate_margin(paths, [0.0125], share=0.9) == 1.0
    # stops from 64 cases only (converge.min_stop_cases): the stop at 48 moves to 64, all honest
    late = replay.stops(paths, {"mfr": 0.0125, "pd": 0.0125}, min_cases=64)
    assert (late["n"] == 64).all() and late["true_within"].all()
    assert replay.calibrate_margin(paths, [0.0125], share=0.95, min_cases=64) == 1.0
