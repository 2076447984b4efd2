"""Sensitivity ranking: Sobol indices against analytic values (a known function, and a GP of noisy
samples of one), band widths against exact ones, ranks only where the draws separate."""
import numpy as np
import pandas as pd
import pytest
import synthetic_cases as syn
from figure_text import pdf_text

from spreadmap import sensitivity
from spreadmap.case.substrate import floor_label
from spreadmap.design import NAMES, bounds, to_physical
from spreadmap.sensitivity import FunctionDraws
from spreadmap.surrogate.models import GPModel
from spreadmap.surrogate.saved_model import SurrogateModel

A, B = 7.0, 0.1  # Ishigami constants
LOW, HIGH = bounds()
C = np.array([2.0, 0.005, 0.02, 0.05])  # linear model on the physical inputs
VAR = (HIGH - LOW) ** 2 / 12.0          # variance of a uniform input


def ishigami(points):
    """Inputs 1-3 mapped to [-pi, pi]; input 4 does not enter."""
    u = (np.asarray(points) - LOW) / (HIGH - LOW)
    x = -np.pi + 2.0 * np.pi * u[:, :3]
    return (np.sin(x[:, 0]) + A * np.sin(x[:, 1]) ** 2 + B * x[:, 2] ** 4 * np.sin(x[:, 0]))[:, None]


def ishigami_analytic():
    v1 = 0.5 * (1.0 + B * np.pi**4 / 5.0) ** 2
    v2 = A**2 / 8.0
    v13 = 8 * B**2 * np.pi**8 / 225
    var = v1 + v2 + v13
    return np.array([v1, v2, 0.0, 0.0]) / var, np.array([v1 + v13, v2, v13, 0.0]) / var


def linear(points):
    return (np.asarray(points, float) @ C)[:, None]


def test_ishigami_indices_lie_in_their_intervals():
    """Deterministic function: the draws differ only by their bootstrap of the Sobol sample, so the
    intervals are the Monte Carlo error; the analytic indices lie inside, the dummy input is 0."""
    table, per_draw = sensitivity.sobol_draws(FunctionDraws(ishigami, ["y"]), ["y"], n=1024, draws=200)
    s1, st = ishigami_analytic()
    got = table.set_index("parameter").loc[list(NAMES)]
    for col, ref in (("S1", s1), ("ST", st)):
        assert np.all(got[f"{col}_low"] <= ref + 1e-12) and np.all(ref - 1e-12 <= got[f"{col}_high"]), (col, got)
    assert np.allclose(got.loc["v_mm_s", ["S1", "ST", "ST_low", "ST_high"]], 0.0, atol=1e-12)
    # x3 acts only through x1: S1 ~ 0, ST ~ 0.24
    assert got.loc["h_um", "ST"] - got.loc["h_um", "S1"] > 0.15
    assert sensitivity.rank_by_draws(per_draw["y"]["ST"]) == ["1", "2", "3", "4"]


def additive_gp(n):
    """GP of n noisy samples of sin(pi u1) + u2^2 + 0.5 u3 (u4 absent); its analytic variances."""
    X = to_physical(np.random.default_rng(2).random((n, 4)))
    u = (X - LOW) / (HIGH - LOW)
    coef = np.array([1.0, 1.0, 0.5, 0.0])
    y = np.column_stack([np.sin(np.pi * u[:, 0]), u[:, 1] ** 2, u[:, 2], np.zeros(n)]) @ coef
    var = coef**2 * np.array([0.5 - 4 / np.pi**2, 4 / 45, 1 / 12, 0.0])  # of sin(pi U), U^2, U
    sd = 0.03 * np.abs(y).mean()
    y = y + np.random.default_rng(3).normal(0, sd, n)
    return SurrogateModel(("y",), {"y": GPModel(inputs="raw").fit(X, y)}, X, LOW, HIGH), var, sd


def test_gp_indices_carry_the_surrogate_uncertainty():
    """A GP of 96 noisy (3 %) samples of an additive function with known indices: each analytic
    index lies in its interval (within 0.01), and so does the noise share."""
    model, var, sd = additive_gp(96)
    table, _ = sensitivity.sobol_draws(model, ["y"], n=256, draws=64)
    got = table.set_index("parameter").loc[list(NAMES)]
    share = var / var.sum()
    assert np.all(got["ST_low"] <= share + 0.01) and np.all(share - 0.01 <= got["ST_high"]), got
    assert np.all(got["S1_low"] <= share + 0.01) and np.all(share - 0.01 <= got["S1_high"]), got
    # the noise share: 3 % noise against the function's variance
    true_share = sd**2 / (sd**2 + var.sum())
    assert got["noise_share_low"].iloc[0] <= true_share * 1.5 and true_share / 1.5 <= got["noise_share_high"].iloc[0]


def test_few_cases_widen_the_intervals_beyond_the_monte_carlo_error():
    """On 20 cases the GP's draws disagree: the indices' intervals are wider than those of its mean
    function alone on the same sample (Monte Carlo error only)."""
    model, _, _ = additive_gp(20)
    gp, _ = sensitivity.sobol_draws(model, ["y"], n=256, draws=64)
    mc, _ = sensitivity.sobol_draws(FunctionDraws(lambda P: model.models["y"].latent(P)[0][:, None], ["y"]), ["y"],
                                    n=256, draws=64)
    assert np.all((gp["ST_high"] - gp["ST_low"]).to_numpy()[:3] > (mc["ST_high"] - mc["ST_low"]).to_numpy()[:3])


def test_noise_share_of_a_known_function():
    fn = FunctionDraws(linear, ["y"], noise_sd={"y": 0.3})
    table, _ = sensitivity.sobol_draws(fn, ["y"], n=512, draws=16)
    fvar = np.sum(C**2 * VAR)
    assert table["noise_share"].iloc[0] == pytest.approx(0.09 / (0.09 + fvar), rel=0.05)


def test_band_widths_of_a_linear_function_are_exact():
    table, per_draw = sensitivity.band_widths(FunctionDraws(linear, ["y"]), ["y"], n_sweep=5, draws=4)
    got = table.set_index("parameter").loc[list(NAMES)]
    np.testing.assert_allclose(got["band"], np.abs(C) * (HIGH - LOW), rtol=1e-12)  # 0.6, 0.2, 0.4, 0.5
    assert sensitivity.rank_by_draws(per_draw["y"]) == ["1", "4", "3", "2"]


def test_ranks_only_what_the_draws_separate():
    rng = np.random.default_rng(0)
    draws = np.column_stack([rng.normal(0.6, 0.02, 500), rng.normal(0.30, 0.05, 500),
                             rng.normal(0.28, 0.05, 500), rng.normal(0.0, 0.01, 500)])
    assert sensitivity.rank_by_draws(draws) == ["1", "2-3", "2-3", "4"]


def test_ranking_table_and_plot(tmp_path):
    model_table = syn.table(40, 0.07)
    X = model_table[list(NAMES)].to_numpy()
    models = {t: GPModel().fit(X, model_table[t].to_numpy(), model_table[f"{t}_sd"].to_numpy()) for t in ("mfr", "pd")}
    model = SurrogateModel(("mfr", "pd"), models, X, LOW, HIGH)
    table = sensitivity.sensitivity(model, ["mfr", "pd"], n=128, draws=16, n_sweep=5)
    assert len(table) == 8 and list(dict.fromkeys(table["target"])) == ["mfr", "pd"]
    # the truth is driven by h/d: d first for both targets, resolved
    for t in ("mfr", "pd"):
        top = table[table["target"] == t].iloc[0]
        assert top["parameter"] == "d_um" and top["rank_ST"] == "1"
    floor = floor_label({"scene": {"substrate": {"kind": "flat"}}})
    paths = sensitivity.plot_ranking(table, tmp_path / "rank", floor)
    assert all(p.stat().st_size > 0 for p in paths.values())
    assert "gap h from the" in pdf_text(paths["pdf"]) and set(pd.read_csv(paths["csv"])["floor"]) == {floor}
    with pytest.raises(ValueError, match="power of 2"):
        sensitivity.sobol_draws(model, ["mfr"], n=100)
