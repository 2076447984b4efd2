"""The surrogate (spreadmap.surrogate) and tools/predict.py, against synthetic cases whose truth
and noise are known (tests/synthetic_cases.py). No YADE."""
from __future__ import annotations

import json
import pickle
import subprocess
import sys
import warnings
from types import SimpleNamespace

import jinja2
import joblib
import numpy as np
import pandas as pd
import pytest
import synthetic_cases as syn
from conftest import ROOT
from sklearn.model_selection import train_test_split

from spreadmap.design import NAMES
from spreadmap.surrogate import fitting, models, prediction, saved_model, settings, study_protocol, validation
from spreadmap.surrogate.cli import cli_main
from spreadmap.surrogate.training_rows import select

TOOL = ROOT / "tools" / "predict.py"
SCRIPT = ROOT / "scripts" / "predict.py"  # the rule predict's entry
PYTHON = str(ROOT / ".venv" / "bin" / "python") if (ROOT / ".venv" / "bin" / "python").exists() else sys.executable
QUICK = {"cv_repeats": 1, "gp_restarts": 0, "learning_curve": False, "mlp_sizes": [4], "mlp_alphas": [1.0],
         "ensemble_members": 4, "neurons": [2, 4], "seeds": [0, 1, 2]}


@pytest.fixture(scope="module")
def result():
    return fitting.fit_surrogate(syn.table(48, 0.07, seed=1), QUICK, log=lambda *a: None)


@pytest.fixture(scope="module")
def saved(result, tmp_path_factory):
    path = tmp_path_factory.mktemp("model") / "model.joblib"
    saved_model.save_model(result.model, path)
    return path


# ------------------------------------------------------------------------------------------------
# validation against a known truth: 3 % and 7 % noise, 64 and 256 Halton points
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("n, rel, with_sd", [(64, 0.03, True), (64, 0.07, False), (256, 0.03, False),
                                             (256, 0.07, True)])
def test_reported_rmse_and_coverage_match_the_truth(n, rel, with_sd):
    """The cross-validated RMSE's interval holds the final model's RMSE against fresh noisy runs;
    its 95 % intervals cover 90-98 % of fresh runs; the noise it reports is the true noise."""
    cfg = settings.make_config({"cv_repeats": 1, "gp_restarts": 0})
    rows = select(syn.table(n, rel, with_sd=with_sd, seed=n), ["mfr", "pd"])
    s = validation.summarise(validation.out_of_fold(rows, "mfr", "gp", cfg), 0.95)
    final = models.GPModel().fit(rows.X, rows.y("mfr"), rows.sd("mfr"))
    X, y = syn.fresh(["mfr"], n=4000, rel=rel)
    mean, _, run_sd = final.predictive(X)
    true_rmse = np.sqrt(np.mean((y["mfr"] - mean) ** 2))
    assert s["rmse_low"] <= true_rmse <= s["rmse_high"], (s, true_rmse)
    assert 0.90 <= np.mean(np.abs(y["mfr"] - mean) <= 1.96 * run_sd) <= 0.98
    true_noise = np.sqrt(np.mean(syn.noise_sd(rows.X, "mfr", rel) ** 2))
    assert s["noise_sd"] == pytest.approx(true_noise, rel=0.15)
    assert s["noise_source"] == ("measured" if with_sd else "model")
    # the ceiling: R^2 can't beat 1 - noise var / var(y), and the error of the mean is below the noise
    assert s["r2"] < s["r2_max"] < 1 and s["mean_error_sd"] < s["noise_sd"]


def test_mlp_ensemble_intervals_cover_fresh_runs():
    """The bootstrap MLP ensemble with per-case noise: 90-98 % of fresh noisy runs inside its 95 %
    intervals, and an error of the mean below the noise (it does not chase the noise)."""
    rows = select(syn.table(64, 0.07, seed=5), ["mfr", "pd"])
    m = models.MLPModel(sizes=[4, 8], alphas=[0.1, 1.0], members=8).fit(rows.X, rows.y("mfr"), rows.sd("mfr"))
    X, y = syn.fresh(["mfr"], n=4000, rel=0.07)
    mean, _, run_sd = m.predictive(X)
    assert 0.90 <= np.mean(np.abs(y["mfr"] - mean) <= 1.96 * run_sd) <= 0.98
    assert np.sqrt(np.mean((mean - syn.truth_mfr(X)) ** 2)) < np.sqrt(np.mean(syn.noise_sd(X, "mfr", 0.07) ** 2))


def test_no_case_is_predicted_by_a_model_that_saw_it(monkeypatch):
    """Every choice inside the folds: each fitted model's training cases exclude the cases it predicts."""
    seen = []
    real = validation.make_model

    class Spy:
        def __init__(self, inner):
            self.inner = inner

        def fit(self, X, y, sd=None):
            self.X = X
            self.inner.fit(X, y, sd)
            return self

        def predictive(self, X):
            seen.append((self.X, X))
            return self.inner.predictive(X)

        def noise_sd(self, X):
            return self.inner.noise_sd(X)

    monkeypatch.setattr(validation, "make_model", lambda kind, cfg: Spy(real(kind, cfg)))
    rows = select(syn.table(30, 0.07), ["mfr"])
    cfg = settings.make_config({"cv_repeats": 2, "mlp_sizes": [2, 4], "mlp_alphas": [1.0], "ensemble_members": 2})
    oof = validation.out_of_fold(rows, "mfr", "mlp", cfg)
    assert len(seen) == 10 and len(oof) == 60 and oof["case_id"].value_counts().eq(2).all()
    for train, test in seen:
        assert not (train[:, None, :] == test[None, :, :]).all(axis=2).any()


# ------------------------------------------------------------------------------------------------
# models
# ------------------------------------------------------------------------------------------------
def test_gp_model_sd_is_the_signal_posterior_without_the_noise():
    rows = select(syn.table(40, 0.07, with_sd=False), ["mfr"])
    m = models.GPModel().fit(rows.X, rows.y("mfr"))
    X = syn.fresh(["mfr"], n=30)[0]
    mean, msd = m.latent(X)
    mu, sd = m.gp_.predict(m.scale_(X), return_std=True)  # scikit-learn's own: signal + white noise
    np.testing.assert_allclose(mean, m.y_mean_ + m.y_sd_ * mu, rtol=1e-10)
    np.testing.assert_allclose(sd**2 * m.y_sd_**2, msd**2 + m.noise_sd(X) ** 2, rtol=1e-8)
    draws = m.draws(X, 4000, np.random.default_rng(0))
    np.testing.assert_allclose(draws.mean(axis=0), mean, atol=4 * msd.max() / np.sqrt(4000) * 3)
    np.testing.assert_allclose(draws.std(axis=0), msd, rtol=0.08)


def test_per_case_noise_is_the_gp_alpha_and_the_noise_of_a_new_run():
    df = syn.table(40, 0.07)
    X = df[list(NAMES)].to_numpy()
    df["mfr_sd"] = np.exp(-4 + 0.02 * X[:, 3] - 0.5 * np.log(X[:, 1]))  # a known log-linear noise law
    rows = select(df, ["mfr"])
    m = models.GPModel(inputs="raw").fit(rows.X, rows.y("mfr"), rows.sd("mfr"))
    np.testing.assert_allclose(m.gp_.alpha, (rows.sd("mfr") / m.y_sd_) ** 2)
    # the noise SD at new points follows the cases' law (plus whatever excess the GP found, tiny here)
    Xn = syn.fresh(["mfr"], n=20)[0]
    law = np.exp(-4 + 0.02 * Xn[:, 3] - 0.5 * np.log(Xn[:, 1]))
    assert m.describe()["per_case_noise"]
    np.testing.assert_allclose(m.case_noise_.sd(m.scale_(Xn)), law, rtol=0.35)
    assert np.all(m.noise_sd(Xn) >= m.case_noise_.sd(m.scale_(Xn)))


def test_case_noise_from_few_degree_of_freedom_sds_predicts_the_variance_not_its_geometric_mean():
    """The known truth: sigma(z) = exp(-4 + 0.3 z1); each case states an SD estimated from 2
    degrees of freedom (sigma sqrt(chi2_2 / 2), as the layer measures' jackknife over 3 blocks
    does). The predicted SD must be sigma (the root mean square), where the plain log fit gives
    the geometric mean, exp(E ln s) = sigma exp((psi(1) - ln 1) / 2) = 0.75 sigma."""
    from scipy.special import digamma

    from spreadmap.surrogate.noise_sd import CaseNoise

    rng = np.random.default_rng(8)
    Z = rng.normal(size=(4000, 4))
    sigma = np.exp(-4 + 0.3 * Z[:, 0])
    sd = sigma * np.sqrt(rng.chisquare(2, len(Z)) / 2)
    fit = CaseNoise().fit(Z, sd)
    Zn = rng.normal(size=(50, 4))
    truth = np.exp(-4 + 0.3 * Zn[:, 0])
    np.testing.assert_allclose(fit.sd(Zn), truth, rtol=0.06)
    geometric = np.exp(fit.coef_[0] + Zn @ fit.coef_[1:])
    np.testing.assert_allclose(geometric / truth, np.exp(digamma(1.0) / 2), rtol=0.06)


def test_targets_auto_takes_the_layer_columns_present():
    cols = ["mfr", "pd", "coverage", "other"]
    assert settings.resolve_targets("auto", cols) == ["mfr", "pd", "coverage"]
    assert settings.resolve_targets(["pd"], cols) == ["pd"]
    with pytest.raises(ValueError, match="roughness_d"):
        settings.resolve_targets(["mfr", "roughness_d"], cols)


def test_config_errors_name_the_key():
    with pytest.raises(ValueError, match=r"unknown surrogate config key\(s\) \['neuron'\]"):
        settings.make_config({"neuron": [8]})
    with pytest.raises(ValueError, match="surrogate.model"):
        settings.make_config({"model": "forest"})
    with pytest.raises(ValueError, match=r"maps.sobol_n: 1000 is not one of \[64, 128"):
        settings.map_config({"sobol_n": 1000})


def test_validating_config_yaml_imports_no_scikit_learn():
    code = ("import sys; from spreadmap import config; config.load('config.yaml'); "
            "print('sklearn' in sys.modules)")
    r = subprocess.run([PYTHON, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
                       env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "False"


def test_excluded_rows_are_counted():
    df = syn.table(30, 0.07)
    df.loc[[1, 2], "status"] = "failed"
    df.loc[[3], "status"] = "blown"
    df.loc[[4, 5, 6], "flagged"] = True
    df.loc[7, "pd"] = np.nan
    rows = select(df, ["mfr", "pd"])
    assert rows.exclusions == {"failed": 2, "blown": 1, "flagged": 3, "nonfinite": 1}
    assert len(rows) == 23 and not {f"lds-{i:05d}" for i in range(1, 8)} & set(rows.frame["case_id"])


# ------------------------------------------------------------------------------------------------
# the study's protocol and the trained surrogate
# ------------------------------------------------------------------------------------------------
def test_study_protocol_is_the_studys(result):
    runs = result.study_runs
    assert sorted(runs["neurons"].unique()) == QUICK["neurons"] and sorted(runs["seed"].unique()) == [0, 1, 2]
    tr, te = train_test_split(np.arange(48), test_size=0.2, random_state=0)
    assert (runs["n_test"] == len(te)).all() and (runs["n_train"] == len(tr)).all()
    net = study_protocol.study_mlp(8, 3)
    assert net.regressor[-1].hidden_layer_sizes == (8,) and net.regressor[-1].random_state == 3
    assert type(net.regressor[0]).__name__ == type(net.transformer).__name__ == "StandardScaler"


def test_fit_reports_both_models_against_the_noise(result):
    v = result.validation
    assert set(zip(v["target"], v["model"])) == {(t, k) for t in ("mfr", "pd") for k in ("gp", "mlp")}
    assert (v.groupby("target")["map_model"].sum() == 1).all()
    assert set(v.loc[v["map_model"], "model"]) == {"gp"}  # the config's choice
    # the noise the table states (its mfr_sd column) is what the errors are measured against
    rows = select(syn.table(48, 0.07, seed=1), ["mfr"])
    mfr = v[(v["target"] == "mfr") & (v["model"] == "gp")].iloc[0]
    assert mfr["noise_sd"] == pytest.approx(np.sqrt(np.mean(rows.sd("mfr") ** 2)))
    meta = json.loads(json.dumps(result.model.metadata))
    assert meta["map_model"] == {"mfr": "gp", "pd": "gp"} and meta["n_usable"] == 48


def test_mlp_draws_the_maps_when_configured():
    r = fitting.fit_surrogate(syn.table(30, 0.07, seed=2), {**QUICK, "model": "mlp"}, log=lambda *a: None)
    assert {r.model.kind(t) for t in r.model.targets} == {"mlp"}
    assert len(r.model.models["mfr"].nets_) == QUICK["ensemble_members"]


def test_plots_written(result, tmp_path):
    from figure_text import pdf_text

    from spreadmap.case.substrate import floor_label
    from spreadmap.surrogate.plots import plot_all

    floor = floor_label({"scene": {"substrate": {"kind": "rough", "jitter": 0.5}}})
    files = plot_all(result, tmp_path, floor=floor)
    for name in ("parity", "r2_vs_neurons", "learning_curve"):
        for suffix in ("png", "pdf", "csv"):
            assert files[name][suffix].stat().st_size > 0
        assert "(previous layer, jitter 0.5 R)" in pdf_text(files[name]["pdf"])  # the figures name their floor
        table = pd.read_csv(files[name]["csv"])  # (an empty learning curve: the column, no rows)
        assert table.columns[-1] == "floor" and set(table["floor"]) <= {floor}
    assert not (tmp_path / "surrogate_metrics.csv").exists()  # the tables are the caller's to write


def test_parity_redraws_from_its_csvs(result, tmp_path):
    """The parity figure's numbers are validation.parity_table's (each case's out-of-fold mean over
    the repeats, here recomputed with pandas), and the figure drawn again from its CSV and the
    metrics CSV read back from disk is the same, byte for byte."""
    from spreadmap.surrogate.plots import plot_parity

    table = validation.parity_table(result.validation, result.oof)
    gp = result.oof[(result.oof["model"] == "gp") & (result.oof["target"] == "pd")]
    pd_rows = table[table["target"] == "pd"].set_index("case_id")
    np.testing.assert_allclose(pd_rows["mean"], gp.groupby("case_id")["mean"].mean().loc[pd_rows.index], rtol=1e-12)
    assert set(table["model"]) == {"gp"} and list(dict.fromkeys(table["target"])) == ["mfr", "pd"]
    result.validation.to_csv(tmp_path / "metrics.csv", index=False)
    first = plot_parity(result.validation, table, tmp_path / "first" / "parity")
    again = plot_parity(pd.read_csv(tmp_path / "metrics.csv"), pd.read_csv(first["csv"]), tmp_path / "again" / "parity")
    for ext in ("png", "csv"):
        assert again[ext].read_bytes() == first[ext].read_bytes(), ext


@pytest.mark.parametrize("caption", ["parity", "r2_vs_neurons", "learning_curve"])
def test_report_captions_state_the_config(caption):
    cfg = {"surrogate": {"neurons": [3, 5], "seeds": [0, 1, 2, 3, 4], "test_fraction": 0.25, "cv_folds": 4,
                         "cv_repeats": 2, "interval": 0.9, "model": "gp", "inputs": "physics"}, "preset": "fast"}
    text = jinja2.Template((ROOT / "rules" / "captions" / f"{caption}.rst").read_text()).render(
        snakemake=SimpleNamespace(config=cfg))
    assert "three" not in text and "20 %" not in text
    if caption == "r2_vs_neurons":
        assert "[0, 1, 2, 3, 4]" in text and "25 %" in text
    else:
        assert "4-fold" in text


# ------------------------------------------------------------------------------------------------
# saved model and prediction
# ------------------------------------------------------------------------------------------------
def test_save_load_predict(result, saved):
    model = saved_model.load_model(saved)
    X = syn.fresh(["mfr"], n=5)[0]
    out = prediction.predict(model, pd.DataFrame(X, columns=list(NAMES)))
    stats = result.model.predict_stats(X)
    for t in ("mfr", "pd"):
        np.testing.assert_allclose(out[t], stats[t][0])
        assert (out[f"{t}_run_sd"] > out[f"{t}_model_sd"]).all()  # a new run adds its noise
    assert json.loads(saved_model.sidecar_path(saved).read_text())["n_usable"] == 48
    assert model(X).shape == (5, 2)


@pytest.mark.parametrize("content", [b"not a pickle at all", b"\x80\x04\x95", None])
def test_corrupt_or_foreign_model_file_is_one_line(tmp_path, content, capsys):
    path = tmp_path / "model.joblib"
    if content is None:
        joblib.dump({"weights": [1, 2, 3]}, path)  # a foreign joblib file
    else:
        path.write_bytes(content)
    with pytest.raises(saved_model.ModelFileError):
        saved_model.load_model(path)
    code = cli_main([str(path), "--point", "f=0.3", "d_um=30", "h_um=60", "v_mm_s=8"])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("predict.py: error:") and err.count("\n") == 1 and "Traceback" not in err


def test_cli_reads_the_readme_points_format(saved, tmp_path):
    pts = tmp_path / "points.csv"
    pts.write_text("name,f,d_um,h_um,v_mm_s,preset,seed\nnormal,0.30,30,65,10,default,1\n"
                   "small,0.30,12,65,10,,\n")
    out = tmp_path / "pred.csv"
    r = subprocess.run([PYTHON, str(TOOL), str(saved), "--csv", str(pts), "--out", str(out)], cwd=ROOT,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    pred = pd.read_csv(out)
    assert pred["name"].tolist() == ["normal", "small"]
    assert {"mfr", "mfr_model_sd", "mfr_run_sd", "pd", "pd_run_sd", "supported"} <= set(pred.columns)


def test_far_points_and_narrow_gaps_are_warned_about(result):
    pts = pd.DataFrame({"f": [0.3, 2.0, 0.3], "d_um": [30, 30, 80], "h_um": [65, 65, 55], "v_mm_s": [10, 10, 10]})
    with pytest.warns(prediction.OutOfRangeWarning) as rec:
        out = prediction.predict(result.model, pts)
    msgs = " | ".join(str(w.message) for w in rec)
    assert "design range of f" in msgs and "f = 2" in msgs
    assert "narrower than one particle" in msgs and "h = 55 um < d = 80 um" in msgs
    assert out["supported"].tolist() == [True, False, False]
    assert out["gap_below_d"].tolist() == [False, False, True]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        prediction.predict(result.model, pts.iloc[[0]])  # inside: no warning


@pytest.mark.parametrize("point, match", [
    ({"f": -0.1}, "friction coefficient cannot be negative"),
    ({"f": 6.0}, "friction coefficient above 5"),
    ({"d_um": 0.0}, "d_um = 0 is refused"),
    ({"h_um": -5.0}, "h_um = -5 is refused"),
    ({"v_mm_s": 0.0}, "v_mm_s = 0 is refused"),
])
def test_physically_meaningless_points_are_refused(result, point, match):
    p = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0, **point}
    with pytest.raises(ValueError, match=match):
        prediction.predict(result.model, p)
    assert cli_main(["unused.joblib", "--point", *[f"{k}={v}" for k, v in p.items()]]) == 2


@pytest.mark.parametrize("points, match", [
    ([[0.3, 30.0, 60.0, np.nan]], "non-finite value nan for parameter 'v_mm_s'"),
    ([[0.3, 30.0, 60.0]], "4 columns"),
    ([[0.3, "thirty", 60.0, 8.0]], "'d_um' must be numeric"),
    (pd.DataFrame({"f": [0.3], "d_um": [30.0], "h_um": [60.0]}), r"missing column\(s\) \['v_mm_s'\]"),
    (pd.DataFrame({"f": [0.3], "d": [30.0], "h_um": [60.0], "v_mm_s": [8.0]}), r"unknown column\(s\) \['d'\]"),
    (np.empty((0, 4)), "no points"),
])
def test_malformed_points_are_refused(result, points, match):
    with pytest.raises(ValueError, match=match):
        prediction.predict(result.model, points)


def test_snakemake_entry_writes_predictions_and_log(saved, tmp_path):
    import runpy

    out, log = tmp_path / "o" / "pred.csv", tmp_path / "pred.log"
    smk = SimpleNamespace(input=SimpleNamespace(model=str(saved), points=None), output=[str(out)], log=[str(log)],
                          params=SimpleNamespace(points=["f=0.2 d_um=20 h_um=60 v_mm_s=10",
                                                         {"f": 0.4, "d_um": 80, "h_um": 70, "v_mm_s": 12}]))
    runpy.run_path(str(SCRIPT), init_globals={"snakemake": smk}, run_name="__main__")
    assert len(pd.read_csv(out)) == 2
    assert "design range of d_um" in log.read_text()


def test_old_format_model_is_refused(result, tmp_path):
    import copy

    old = copy.copy(result.model)
    old.format = "spreadmap-surrogate/1"
    path = tmp_path / "old.joblib"
    with open(path, "wb") as fh:
        pickle.dump(old, fh)
    with pytest.raises(saved_model.ModelFileError, match="retrain"):
        saved_model.load_model(path)


def test_layer_quality_columns_become_targets_with_or_without_their_sd():
    """A table with the layer-quality columns: `auto` models them too (coverage with its own SD
    column, roughness_d without one, its noise then fitted), and the machine map picks its y axis."""
    from spreadmap import maps

    df = syn.table(30, 0.07, seed=6)
    rng = np.random.default_rng(6)
    X = df[list(NAMES)].to_numpy()
    df["coverage"] = 0.7 + 0.2 * (X[:, 3] - 5) / 10 + rng.normal(0, 0.02, 30)  # set by the speed, not MFR
    df["coverage_sd"] = 0.02
    df["roughness_d"] = 0.3 + 0.5 * df["mfr"] + rng.normal(0, 0.01, 30)
    r = fitting.fit_surrogate(df, {**QUICK, "model": "gp"}, log=lambda *a: None)
    assert r.model.targets == ("mfr", "pd", "coverage", "roughness_d")
    v = r.validation.set_index(["target", "model"])
    assert v.loc[("coverage", "gp"), "noise_source"] == "measured"
    assert v.loc[("roughness_d", "gp"), "noise_source"] == "model"
    assert v.loc[("coverage", "gp"), "noise_sd"] == pytest.approx(0.02)
    assert maps.choose_machine_y(df, r.model.targets)[0] == "coverage"


def test_coverage_verdict_reads_the_interval_not_the_point():
    """Coverage whose interval excludes the nominal level is too wide or too narrow, not a success:
    the study's 97.5 % (95.7-98.9) of 95 % intervals is too wide; an interval holding 95 % is
    consistent whatever its point value; the verdict reaches the validation table."""
    from spreadmap.surrogate.validation import coverage_verdict

    assert coverage_verdict(0.957, 0.989, 0.95) == "too wide"
    assert coverage_verdict(0.80, 0.93, 0.95) == "too narrow"
    assert coverage_verdict(0.90, 0.99, 0.95) == coverage_verdict(0.949, 0.951, 0.95) == "consistent"
    assert coverage_verdict(float("nan"), 0.99, 0.95) == "unknown"
    # an independent check: 100 cases all inside their 95 % intervals; the exact binomial (Clopper-
    # Pearson) 95 % interval of 100/100 is 0.964-1.0, above 0.95: too wide
    from scipy.stats import binomtest

    ci = binomtest(100, 100).proportion_ci(0.95)
    assert coverage_verdict(ci.low, ci.high, 0.95) == "too wide"
    ci = binomtest(95, 100).proportion_ci(0.95)
    assert coverage_verdict(ci.low, ci.high, 0.95) == "consistent"
