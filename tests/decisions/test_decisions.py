"""Recommended settings (spreadmap.decisions) on a synthetic model whose posterior is known in
closed form, and the errors that name their config key.

The synthetic model's mean functions are linear (coverage) or quadratic (pd); its posterior draws
of the mean are mean + sigma Z with one Z shared by every point (taken at the n midpoint
quantiles of the normal, so the draws' averages are quadrature, not Monte Carlo); a new run adds
noise of SD s. Then, for a lower bound lo on coverage c, the probability is
Phi((c - lo) / sqrt(sigma^2 + s^2)) for a new run and Phi((c - lo) / sigma) for the mean, and
with a powder range the worst powder (the lowest c) decides. The fastest setting meeting a
confidence p sits where c = lo + S Phi^-1(p): written out below, not taken from the code."""
import copy

import numpy as np
import pandas as pd
import pytest
import yaml
from conftest import ROOT
from figure_text import pdf_text
from scipy.stats import norm

from spreadmap import config as spreadmap_config
from spreadmap.case.substrate import floor_label
from spreadmap.decisions import DecisionError, decision_config, recommendations
from spreadmap.decisions.explorer import write_explorer
from spreadmap.decisions.feasibility import powders_from_config
from spreadmap.decisions.figure import decision_figure

SIGMA, NOISE = 0.01, 0.02            # model SD and a run's noise SD of coverage
LOW, HIGH = np.array([0.15, 10.0, 55.0, 5.0]), np.array([0.45, 50.0, 75.0, 15.0])
SUPPORT = {"max_distance": 1.5, "max_sd_ratio": 1.0}


def coverage(f, d, h, v):
    return 0.9 + 0.01 * (h - 65) - 0.02 * (v - 10) - 0.004 * (d - 20) - 0.1 * (f - 0.3)


def quality(f, d, h, v):
    return 0.5 - 0.001 * (h - 62) ** 2 - 0.001 * (v - 7) ** 2 - 0.002 * d


class KnownModel:
    """The interface of SurrogateModel that decisions use, with a posterior known analytically."""

    targets = ("coverage", "pd")
    design_low, design_high = LOW, HIGH

    def __init__(self, far=lambda h, v: np.zeros_like(h, bool)):
        self.far = far  # settings beyond the data: distance 3 case spacings there, 0.5 elsewhere
        grid = np.meshgrid(np.linspace(0.15, 0.45, 4), np.linspace(15, 40, 6), [60.0, 70.0], [8.0, 12.0], indexing="ij")
        self.train_X = np.column_stack([g.ravel() for g in grid])  # the data span d 15-40 um

    def spacing(self):
        return 0.05

    def _means(self, X):
        X = np.asarray(X, float)
        return {"coverage": coverage(*X.T), "pd": quality(*X.T)}

    def predict_stats(self, X):
        n = len(X)
        run = np.sqrt(SIGMA**2 + NOISE**2)
        return {t: (m, np.full(n, SIGMA), np.full(n, run)) for t, m in self._means(X).items()}

    def data_distance(self, X):
        X = np.asarray(X, float)
        return np.where(self.far(X[:, 2], X[:, 3]), 3.0, 0.5)

    def draws(self, X, n, seed=0, targets=None):
        z = norm.ppf((np.arange(n) + 0.5) / n)[:, None]
        means = self._means(X)
        return {t: means[t][None, :] + SIGMA * z for t in (targets or self.targets)}


def settings(**changes):
    dec = {"confidence": 0.9, "about": "run", "draws": 4000, "bounds": {"coverage": {"min": 0.9}},
           "quality": {"target": "pd", "goal": "max"},
           "machine": {"h_um": [55, 75], "v_mm_s": [5, 15], "n_h": 11, "n_v": 21},
           "powders": {"one": {"f": 0.3, "d_um": 20}}}
    dec.update(changes)
    return decision_config(dec)


def fastest_by_hand(dec, scale, c_of):
    """The fastest grid setting whose closed-form probability reaches the confidence (and which
    the model's data support), from the boundary c = lo + scale Phi^-1(p)."""
    need = 0.9 + scale * norm.ppf(dec["confidence"])
    h = np.linspace(55, 75, dec["machine"]["n_h"])
    v = np.linspace(5, 15, dec["machine"]["n_v"])
    best = None
    for hh in h:
        for vv in v:
            if c_of(hh, vv) >= need and (best is None or vv > best[1]):
                best = (hh, vv)
    return best, need


def test_probability_and_fastest_setting_match_the_closed_form_for_a_new_run():
    dec = settings()
    table, grids = recommendations(KnownModel(), dec, SUPPORT)
    grid = grids["one"]
    S = np.hypot(SIGMA, NOISE)
    expected = norm.cdf((coverage(0.3, 20, grid["h_um"], grid["v_mm_s"]) - 0.9) / S)
    np.testing.assert_allclose(grid["probability"], expected, atol=1e-3)
    # the boundary v*(h) where P = 0.9: v* = 10 + (0.01 (h - 65) - S z_0.9) / 0.02 (f 0.3, d 20)
    (h_fast, v_fast), _ = fastest_by_hand(dec, S, lambda h, v: coverage(0.3, 20, h, v))
    fastest = table[(table["kind"] == "fastest") & (table["status"] == "recommended")].iloc[0]
    assert (fastest["h_um"], fastest["v_mm_s"]) == (h_fast, v_fast) == (75.0, 13.5)
    assert fastest["probability"] >= 0.9 and bool(fastest["recommended"])
    assert norm.cdf((coverage(0.3, 20, 75, 14.0) - 0.9) / S) < 0.9  # the next grid speed would not do


def test_mean_semantics_and_a_powder_range_take_the_worst_powder_and_the_best_quality():
    dec = settings(about="mean", powders={"range": {"f": [0.3, 0.4], "d_um": [20, 30]}})
    table, grids = recommendations(KnownModel(), dec, SUPPORT)
    grid = grids["range"]
    worst = coverage(0.4, 30, grid["h_um"], grid["v_mm_s"])  # c falls with f and d: the range's corner
    np.testing.assert_allclose(grid["probability"], norm.cdf((worst - 0.9) / SIGMA), atol=1e-3)
    (h_fast, v_fast), need = fastest_by_hand(dec, SIGMA, lambda h, v: coverage(0.4, 30, h, v))
    rows = table.set_index("kind")
    assert (rows.loc["fastest", "h_um"], rows.loc["fastest", "v_mm_s"]) == (h_fast, v_fast)
    # best quality: pd peaks at h 62, v 7, where the worst powder's coverage is below the boundary,
    # so the best feasible setting is the grid point nearest the peak on the feasible side
    h = np.linspace(55, 75, 11)
    v = np.linspace(5, 15, 21)
    feasible = [(hh, vv) for hh in h for vv in v if coverage(0.4, 30, hh, vv) >= need]
    best = max(feasible, key=lambda p: quality(0.4, 30, *p))
    assert coverage(0.4, 30, 62, 7) < need  # the unconstrained optimum is not feasible
    assert (rows.loc["best_quality", "h_um"], rows.loc["best_quality", "v_mm_s"]) == best
    assert rows.loc["best_quality", "quality"] == pytest.approx(quality(0.4, 30, *best))  # worst over the range


def test_settings_beyond_the_data_are_marked_and_never_recommended():
    model = KnownModel(far=lambda h, v: h >= 71)  # the data stop below h = 71 um
    dec = settings()
    table, grids = recommendations(model, dec, SUPPORT)
    S = np.hypot(SIGMA, NOISE)
    (h_fast, v_fast), _ = fastest_by_hand(dec, S, lambda h, v: coverage(0.3, 20, h, v) if h < 71 else -1)
    rec = table[(table["kind"] == "fastest") & table["recommended"]].iloc[0]
    assert (rec["h_um"], rec["v_mm_s"]) == (h_fast, v_fast) and h_fast < 71 and not rec["beyond_data"]
    beyond = table[(table["kind"] == "fastest") & (table["status"] == "beyond_data")].iloc[0]
    assert beyond["h_um"] >= 71 and beyond["v_mm_s"] > v_fast and not beyond["recommended"]
    assert "NOT recommended" in beyond["note"]
    assert grids["one"]["beyond_data"].to_numpy().sum() == (np.linspace(55, 75, 11) >= 71).sum() * 21
    # nowhere but beyond the data: no recommendation at all
    table, _ = recommendations(KnownModel(far=lambda h, v: np.ones_like(h, bool)), dec, SUPPORT)
    assert set(table["status"]) == {"beyond_data_only"} and not table["recommended"].any()


def test_bounds_no_setting_meets_are_reported_with_the_best_probability():
    dec = settings(bounds={"coverage": {"min": 1.2}})
    table, grids = recommendations(KnownModel(), dec, SUPPORT)
    S = np.hypot(SIGMA, NOISE)
    best = norm.cdf((coverage(0.3, 20, 75, 5) - 1.2) / S)  # the highest coverage of the grid
    assert set(table["status"]) == {"none_meets"} and not table["recommended"].any()
    assert table["best_probability_in_data"].iloc[0] == pytest.approx(best, abs=1e-3)
    assert (table["h_um"].iloc[0], table["v_mm_s"].iloc[0]) == (75.0, 5.0)
    assert "no setting meets the bounds with P >= 0.9" in table["note"].iloc[0]


def test_the_figure_is_written_and_names_its_floor(tmp_path):
    dec = settings(powders={"one": {"f": 0.3, "d_um": 20}, "none": {"f": 0.45, "d_um": 40}})
    table, grids = recommendations(KnownModel(), dec, SUPPORT)
    floor = floor_label({"scene": {"substrate": {"kind": "rough", "jitter": 0.5}}})
    paths = decision_figure(grids, table, powders_from_config(dec), dec, SUPPORT, tmp_path / "probability", floor)
    assert all(p.stat().st_size > 1000 for p in paths.values())
    assert "(previous layer, jitter 0.5 R); gap h nominal, from its tops" in pdf_text(paths["pdf"])
    assert set(pd.read_csv(paths["csv"])["floor"]) == {floor}


def test_the_explorer_page_and_its_table_name_the_floor(tmp_path):
    dec = settings(explorer={"n_f": 2, "n_d": 2, "n_h": 3, "n_v": 3})
    floor = floor_label({"scene": {"substrate": {"kind": "flat"}}})
    write_explorer(KnownModel(), dec, SUPPORT, tmp_path / "explorer.html", tmp_path / "explorer.csv", floor=floor)
    page = (tmp_path / "explorer.html").read_text()
    assert f'<p id="floor"><b>{floor}</b></p>' in page
    assert set(pd.read_csv(tmp_path / "explorer.csv")["floor"]) == {floor}


@pytest.mark.parametrize("change, key", [
    ({"bounds": {"roughness_d": {"max": 0.5}}}, "decisions.bounds.roughness_d"),
    ({"quality": {"target": "mfr", "goal": "max"}}, "decisions.quality.target"),
    ({"powders": {"big": {"f": 0.3, "d_um": 48}}}, "decisions.powders.big.d_um"),
])
def test_what_the_model_cannot_answer_is_refused_naming_the_key(change, key):
    with pytest.raises(DecisionError, match=key.replace(".", r"\.")) as error:
        recommendations(KnownModel(), settings(**change), SUPPORT)
    assert ("no target" in str(error.value)) or ("outside the model's data" in str(error.value))


def test_machine_range_outside_the_models_design_space_is_refused():
    model = KnownModel()
    model.design_low = np.array([0.15, 10.0, 60.0, 5.0])  # a model trained on h from 60 um
    with pytest.raises(DecisionError, match=r"decisions\.machine\.h_um.*outside the model's design space"):
        recommendations(model, settings(), SUPPORT)


@pytest.fixture()
def raw_config():
    return yaml.safe_load((ROOT / "config.yaml").read_text())


@pytest.mark.parametrize("section, key, message", [
    ({"machine": {"h_um": [50, 75]}}, "decisions.machine.h_um", "outside the design space"),
    ({"machine": {"v_mm_s": [12, 8]}}, "decisions.machine.v_mm_s", "reversed"),
    ({"bounds": {"density": {"min": 0.5}}}, "decisions.bounds.density", "not a target the surrogate can have"),
    ({"bounds": {"mfr": {"min": 0.5, "max": 0.4}}}, "decisions.bounds.mfr", "must be below"),
    ({"powders": {"p": {"f": 0.3, "d_um": [5, 20]}}}, "decisions.powders.p.d_um", "outside the design space"),
    ({"quality": {"target": "speed"}}, "decisions.quality.target", "not a target"),
    ({"confidence": 1.0}, "decisions.confidence", "must be < 1"),
])
def test_bad_decisions_config_is_refused_naming_the_key(raw_config, section, key, message):
    config = copy.deepcopy(raw_config)
    config["decisions"] = {**config.get("decisions", {}), **section}
    with pytest.raises(spreadmap_config.ConfigError) as error:
        spreadmap_config.validate(config)
    assert key in str(error.value) and message in str(error.value), str(error.value)


def test_the_shipped_decisions_config_is_valid_and_complete(raw_config):
    config = spreadmap_config.validate(copy.deepcopy(raw_config))
    dec = decision_config(config["decisions"])
    assert dec["powders"] and dec["bounds"] and 0 < dec["confidence"] < 1 and dec["about"] in ("run", "mean")


@pytest.mark.parametrize("powder, study_span, message", [
    ({"f": 0.3, "d10_um": 20, "d50_um": 30, "d90_um": 45}, 0.0, "span 0.83 but the study's spheres are one size"),
    ({"f": 0.3, "d50_um": 30, "span": 1.0}, 0.5, "span 1.00 but the study's spheres are span 0.5"),
    ({"f": 0.3, "d_um": 30, "span": 0.2}, 0.0, "span is not a design axis"),
    ({"f": 0.3, "d50_um": 30, "d10_um": 20}, 0.0, "d10_um without d90_um"),
    ({"f": 0.3, "d10_um": 35, "d50_um": 30, "d90_um": 45}, 0.0, "must rise"),
    ({"f": 0.3, "d_um": 30, "d10_um": 20, "d90_um": 45}, 0.0, "go with d50_um"),
])
def test_a_powder_by_its_certificate_is_refused_when_the_maps_do_not_speak_for_its_span(raw_config, powder,
                                                                                        study_span, message):
    config = copy.deepcopy(raw_config)
    config["material"]["size_distribution"] = {"span": study_span}
    config["decisions"]["powders"] = {"cert": powder}
    with pytest.raises(spreadmap_config.ConfigError) as error:
        spreadmap_config.validate(config)
    assert "decisions.powders.cert" in str(error.value) and message in str(error.value), str(error.value)


def test_a_powder_by_its_certificate_reads_as_its_d50_and_span(raw_config):
    # a 15-45 um-like certificate (D10 20, D50 30, D90 45 um): span (45 - 20) / 30 = 0.833, within
    # 0.1 of a study at span 0.9
    config = copy.deepcopy(raw_config)
    config["material"]["size_distribution"] = {"span": 0.9}
    config["decisions"]["powders"] = {"cert": {"f": 0.3, "d10_um": 20, "d50_um": 30, "d90_um": 45},
                                      "by_span": {"f": [0.3, 0.4], "d50_um": 25, "span": 0.95},
                                      "plain": {"f": 0.3, "d_um": [20, 30]}}
    dec = decision_config(spreadmap_config.validate(config)["decisions"])
    cert, by_span, plain = powders_from_config(dec)
    assert cert.d_um == (30.0, 30.0) and cert.span == pytest.approx(25.0 / 30.0) and cert.size_key == "d50_um"
    assert by_span.f == (0.3, 0.4) and by_span.span == 0.95
    assert plain.d_um == (20.0, 30.0) and plain.span is None and plain.size_key == "d_um"
    assert cert.label() == "cert: f 0.3, D50 30 um, span 0.83" and plain.label() == "plain: f 0.3, d 20-30 um"
    config["decisions"]["powders"] = {"both": {"f": 0.3, "d_um": 30, "d50_um": 30}}
    with pytest.raises(spreadmap_config.ConfigError, match="decisions.powders.both"):
        spreadmap_config.validate(config)
