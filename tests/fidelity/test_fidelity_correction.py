"""The preset-to-reference factor (spreadlab.paired_factor): hand-worked random-effects numbers,
a synthetic study of known factor, spread and noise, and the pairing of a fidelity table. No YADE."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from spreadlab.paired_factor import config_block, correction, new_point_interval, pairs, random_effects


def test_random_effects_by_hand():
    # two points 0.1 apart with noise variance 0.01 each: Q = 2 x 100 x 0.05^2 = 0.5 < 1 dof, tau = 0
    r = random_effects([0.0, 0.1], [0.01, 0.01])
    assert r["q"] == pytest.approx(0.5) and r["tau"] == 0.0
    assert r["mu"] == pytest.approx(0.05) and r["se"] == pytest.approx(math.sqrt(0.01 / 2))
    # 0.3 apart: Q = 4.5, tau^2 = (4.5 - 1) / (200 - 100) = 0.035, SE = sqrt((0.01 + 0.035) / 2)
    r = random_effects([0.0, 0.3], [0.01, 0.01])
    assert r["q"] == pytest.approx(4.5) and r["tau"] ** 2 == pytest.approx(0.035)
    assert r["se"] == pytest.approx(math.sqrt(0.045 / 2))
    assert r["q_p"] == pytest.approx(math.erfc(math.sqrt(4.5 / 2)))  # the chi-square(1) tail at 4.5, by hand


@pytest.mark.parametrize("k, tau", [(4, 0.02), (6, 0.0), (6, 0.02), (6, 0.04), (8, 0.02)])
def test_new_point_interval_holds_a_fresh_points_factor(k, tau):
    """k points whose true log factors scatter with SD tau around 0.04, each measured with noise SD
    0.02-0.04: the factor's interval at a point not run (the maps' +-1.96 SD) holds a fresh point's
    true log factor at least 95 % of the time (the points' own noise makes it wide, never narrow)."""
    rng = np.random.default_rng(5)
    mu, reps = 0.04, 4000
    sd = np.linspace(0.02, 0.04, k)
    true = mu + tau * rng.standard_normal((reps, k))
    measured = true + sd * rng.standard_normal((reps, k))
    fresh = mu + tau * rng.standard_normal(reps)
    got = np.array([new_point_interval(row) for row in measured])
    assert got[:, 0].mean() == pytest.approx(mu, abs=4 * math.sqrt((tau**2 + np.mean(sd**2)) / k / reps))
    assert np.mean(np.abs(fresh - got[:, 0]) <= got[:, 2]) >= 0.95


def _table(ratio_by_name: dict, seeds=(1, 2), rel_sd=None) -> pd.DataFrame:
    """A fidelity table: per point (d, h, reference / default) both presets at each seed, each case's
    stated SD rel_sd (per point, or 3 %) of its value."""
    rows = []
    rel = np.broadcast_to(0.03 if rel_sd is None else np.asarray(rel_sd, float), (len(ratio_by_name),))
    for (name, (d, h, ratio)), r in zip(ratio_by_name.items(), rel):
        for s in seeds:
            base = 0.3 + 0.01 * s
            for preset, value in (("default", base), ("reference", base * ratio)):
                rows.append({"name": name, "seed": s, "preset": preset, "status": "ok", "flagged": False,
                             "f": 0.3, "d_um": d, "h_um": h, "v_mm_s": 10.0, "cpu_time": 10.0 if preset == "default" else 80.0,
                             "mfr": value, "mfr_sd": r * value, "pd": value, "pd_sd": r * value})
    return pd.DataFrame(rows)


def test_pairs_and_factor_from_a_table():
    table = _table({"a": (50.0, 55.0, 1.05), "b": (30.0, 65.0, 1.05), "c": (20.0, 60.0, 1.05)})
    # a case the reference flagged leaves its pair out
    table.loc[(table["name"] == "c") & (table["seed"] == 2) & (table["preset"] == "reference"), "flagged"] = True
    p = pairs(table, "default", "reference")
    assert len(p) == 5 and p["mfr_l"].to_numpy() == pytest.approx(np.log(1.05))
    assert p["mfr_v"].to_numpy() == pytest.approx(2 * 0.03**2)
    r = correction(table)
    assert r["pairs"] == 5 and r["points"] == 3 and r["cpu_ratio"] == pytest.approx(8.0)
    t = r["targets"]["mfr"]
    assert t["factor"] == pytest.approx(1.05) and t["sd"] == pytest.approx(0.0, abs=1e-12)
    re = t["random_effects"]
    assert re["tau"] == 0.0 and re["q"] == pytest.approx(0.0, abs=1e-20)
    # the fixed-effect SE: 3 points, variances 0.0018 / 2, / 2 and / 1 (c has one pair)
    assert re["se"] == pytest.approx(1 / math.sqrt(2 / 0.0018 + 2 / 0.0018 + 1 / 0.0018))
    assert config_block(r, "x")["targets"]["pd"] == {"factor": 1.05, "sd": 0.0}
    # three points at 1.02, 1.05, 1.08: the interval of a new point is t(2) x SD x sqrt(4/3) around their mean
    r = correction(_table({"a": (50.0, 55.0, 1.02), "b": (30.0, 65.0, 1.05), "c": (20.0, 60.0, 1.08)}))
    ls = np.log([1.02, 1.05, 1.08])
    half = 4.302653 * np.std(ls, ddof=1) * math.sqrt(4 / 3)
    assert r["targets"]["pd"]["new_point_95"] == pytest.approx([math.exp(ls.mean() - half), math.exp(ls.mean() + half)], rel=1e-6)
