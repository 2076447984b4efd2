"""tools/truth_ladder_report.py (issue 64's pre-registered analysis) on synthetic ladders of known
bias, and its work of separation against scipy's integral of the Hertz-DMT force."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from conftest import script_module
from scipy import integrate, optimize

report = script_module("tools/truth_ladder_report.py")
POINTS = {"coarse": 45.0, "medium": 30.0, "fine": 15.0, "slow": 40.0, "corner": 11.0}
SCALES = {"x1000": 1000.0, "x100": 100.0, "x10": 10.0, "x1": 1.0, "x1000_p0.8": 1000.0, "x1000_p0.6": 1000.0}


def ladder(bias: dict[str, float], spread: float = 0.002, truth: float = 0.30, points=POINTS) -> pd.DataFrame:
    rows = []
    for point, d in points.items():
        for arm, b in bias.items():
            for seed, e in zip((1, 2, 3), (-spread, 0.0, spread)):
                rows.append({"arm": arm, "point": point, "seed": seed, "status": "ok", "flagged": False,
                             "mfr": truth + b + e, "pd": 0.9 * (truth + b) + e, "cpu_time": 10.0 * seed,
                             "f": 0.3, "d_um": d, "h_um": 60.0, "v_mm_s": 10.0, "density_scale": SCALES[arm],
                             "young_pa": 2.1e9, "surface_energy": 1e-4})
    return pd.DataFrame(rows)


def test_the_cheapest_rung_within_noise_is_named():
    cases = ladder({"x1000": -0.05, "x100": -0.02, "x10": 0.001, "x1": 0.0})
    text, result = report.report(cases)
    assert result["level"] == "x10"
    b = result["bias"].set_index(["point", "arm"])
    # SE of a difference of two 3-seed means whose seeds spread -e, 0, +e: sqrt(2) e / sqrt(3)
    assert b.loc[("fine", "x1000"), "mfr_bias"] == pytest.approx(-0.05)
    assert b.loc[("fine", "x1000"), "mfr_se"] == pytest.approx(math.sqrt(2) * 0.002 / math.sqrt(3))
    assert "**x10**" in text


def test_no_rung_is_named_when_all_are_off():
    cases = ladder({"x1000": -0.05, "x100": -0.03, "x10": -0.02, "x1": 0.0})
    assert report.report(cases)[1]["level"] == "x1"  # only the stiffest itself
    # a pooled bias inside noise point by point but consistently beyond the margin fails too
    noisy = ladder({"x1000": -0.05, "x100": -0.03, "x10": -0.012, "x1": 0.0}, spread=0.012)
    level, reasons = report.truth_level(report.biases(report.cell_stats(noisy)), list(POINTS))
    assert level == "x1" and any("pooled" in r for r in reasons if r.startswith("x10"))


def test_flagged_cases_are_left_out_and_counted():
    cases = ladder({"x10": 0.0, "x1": 0.0})
    cases.loc[(cases["arm"] == "x10") & (cases["seed"] == 3), "flagged"] = True
    cells = report.cell_stats(cases).set_index(["point", "arm"])
    assert cells.loc[("coarse", "x10"), "seeds"] == 2 and cells.loc[("coarse", "x10"), "not_usable"] == 1


def test_fitted_exponent_recovers_a_known_one():
    cases = ladder({"x1000": 0.03, "x1000_p0.8": 0.01, "x1000_p0.6": -0.01, "x1": 0.0},
                   points={k: POINTS[k] for k in ("coarse", "medium", "fine")})
    p_star, chi2 = report.fitted_exponent(report.cell_stats(cases), "x1")
    # MFR(p) = truth + 0.1 (p - 0.7): zero bias at p = 0.7
    assert p_star == pytest.approx(0.70)
    assert chi2["chi2"].min() == pytest.approx(0.0, abs=1e-9)


def test_work_of_separation_against_scipy():
    row = {"density_scale": 1000.0, "surface_energy": 1e-4, "young_pa": 2.1e9, "d_um": 20.0, "v_mm_s": 10.0,
           "arm": "x1000"}
    radius, poisson = 10e-6, 0.3
    r_star, e_star = radius / 2, (2.1e9 / 1000.0) / (2 * (1 - poisson ** 2))
    pull = 4 * math.pi * 1e-4 * r_star
    hertz = lambda x: 4 / 3 * e_star * math.sqrt(r_star) * x ** 1.5  # noqa: E731
    delta = optimize.brentq(lambda x: hertz(x) - pull, 0, 1e-5)
    work, _ = integrate.quad(lambda x: pull - hertz(x), 0, delta)
    kinetic = 0.5 * 7980 * math.pi / 6 * (20e-6) ** 3 * 0.01 ** 2
    assert report.work_over_kinetic(row) == pytest.approx(work / kinetic, rel=1e-6)
    # the softer the rung, the stickier: W ~ E^(-2/3)
    stiff = report.work_over_kinetic({**row, "density_scale": 1.0})
    assert report.work_over_kinetic(row) / stiff == pytest.approx(1000.0 ** (2 / 3), rel=1e-9)


def test_collapse_on_a_synthetic_law():
    # relative biases that are a line in log10(W/K) of the rung collapse with R^2 1 on it, not on Bond
    cases = ladder({"x1000": 0.0, "x100": 0.0, "x10": 0.0, "x1": 0.0}, spread=0.0005)
    cells = report.cell_stats(cases)
    for r in cells.itertuples():
        if r.arm != "x1":
            rel = -0.01 - 0.02 * np.log10(report.work_over_kinetic(r._asdict()))
            cases.loc[(cases["point"] == r.point) & (cases["arm"] == r.arm), "mfr"] *= 1 + rel
    cells = report.cell_stats(cases)
    col = report.collapse(report.biases(cells), cells)
    assert col["w_over_k"]["r2"] > 0.99 and col["w_over_k"]["slope"] == pytest.approx(-0.02, rel=0.02)
    assert col["bond"]["r2"] < 0.5
