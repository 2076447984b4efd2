"""spreadlab.experiments.paired and tools/paired_arms.py on a synthetic A/B table of known shifts: the
CPU ratio's geometric mean and the pooled relative shift with their t intervals as scipy computes
them, per-point z from the recorded SDs, unfinished cases unpaired, a flag new in the arm counted."""

import math

import numpy as np
import pandas as pd
import pytest
from conftest import script_module
from scipy import stats

from spreadlab.experiments import paired

tool = script_module("tools/paired_arms.py")


def table() -> pd.DataFrame:
    rng = np.random.default_rng(3)
    rows = []
    for k, point in enumerate(("a", "b", "c", "d")):
        for seed in (1, 2, 3):
            base_mfr = 0.2 + 0.05 * k + rng.normal(0, 0.01)
            cpu = 20.0 * (k + 1) * rng.uniform(0.9, 1.1)
            shift = 0.03 if point == "d" else 0.0  # point d: +0.03, 3 SEs of its recorded SDs
            for arm, mfr, c in (("shipped", base_mfr, cpu), ("lever", base_mfr + shift, 0.8 * cpu * rng.uniform(0.95, 1.05))):
                rows.append({"arm": arm, "point": point, "seed": seed, "status": "ok", "flagged": False,
                             "mfr": mfr, "pd": 0.5 * mfr, "mfr_sd": 0.01 * math.sqrt(1.5), "pd_sd": 0.005,
                             "cpu_time": c, "heap_end_h2": 1.2 + 0.1 * k})
    t = pd.DataFrame(rows)
    t.loc[(t.arm == "lever") & (t.point == "a") & (t.seed == 3), "status"] = "failed"  # unpaired
    t.loc[(t.arm == "lever") & (t.point == "b") & (t.seed == 1), "flagged"] = True
    return t


def test_numbers_against_scipy(tmp_path):
    t = table()
    p = paired.pairs(t, "lever", "shipped")
    assert len(p) == 11  # 12 seeds x points, one lever case failed
    ratios = p["cpu_time_arm"] / p["cpu_time_base"]
    g, lo, hi = paired.cpu_ratio(p)
    ci = stats.ttest_1samp(np.log(ratios), 0.0).confidence_interval(0.95)
    assert g == pytest.approx(stats.gmean(ratios), rel=1e-12)
    assert (lo, hi) == pytest.approx((math.exp(ci.low), math.exp(ci.high)), rel=1e-12)
    rel = (p["mfr_arm"] - p["mfr_base"]) / p["mfr_base"]
    m, mlo, mhi = paired.relative_shift(p, "mfr")
    ci90 = stats.ttest_1samp(rel, 0.0).confidence_interval(0.90)
    assert (m, mlo, mhi) == pytest.approx((rel.mean(), ci90.low, ci90.high), rel=1e-12)
    z = paired.by_point(p, "mfr").set_index("point")["z"]
    assert z["d"] == pytest.approx(3.0, rel=1e-9)  # 0.03 / (sqrt(3 x 2 x 1.5e-4) / 3)
    assert z[["a", "b", "c"]].abs().max() < 1e-9
    csv = tmp_path / "cases.csv"
    t.to_csv(csv, index=False)
    out = tmp_path / "paired.md"
    assert tool.main([str(csv), "--base", "shipped", "--out", str(out)]) == 0
    text = out.read_text()
    assert "**Pairs**: 11 (point, seed) of 12 lever cases at 4 points" in text
    assert "1 pairs flagged in the arm and not in the base (b s1)" in text
    assert "the largest point z +3.00 (d)" in text
    assert "heap at the window's end at least 1.20 h^2" in text


def test_a_bad_base_is_named(tmp_path):
    csv = tmp_path / "cases.csv"
    table().to_csv(csv, index=False)
    with pytest.raises(SystemExit):
        tool.main([str(csv), "--base", "nope"])
