"""Tests of spreadmap.surrogate, spreadmap.surrogate_plots and scripts/predict.py (no YADE)."""
from __future__ import annotations

import hashlib
import json
import runpy
import subprocess
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy.stats import qmc

from spreadmap import design
from spreadmap import surrogate as S
from spreadmap import surrogate_plots as SP

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "predict.py"
PYTHON = str(ROOT / ".venv" / "bin" / "python") if (ROOT / ".venv" / "bin" / "python").exists() else sys.executable

N_CASES = 215
BAD = {"failed": [3, 40, 77], "blown": [11, 150], "flagged": [20, 99, 180, 201], "nonfinite": [60]}
FAST = dict(neurons=[4, 8, 16, 32], seeds=[0, 1, 2], cv_all_neurons=False, gp_restarts=1,
            learning_curve=[50, 100, N_CASES], ensemble_members=4)


def mfr_like(u: np.ndarray) -> np.ndarray:
    """Smooth saturating function of the unit-scaled inputs: falls with friction, particle size
    and speed, rises with the gap; range about 0.07-0.60."""
    f, d, h, v = u.T
    return 0.70 / (1.0 + np.exp(-(1.5 - 2.5 * d + 1.0 * h - 1.2 * f - 0.6 * v))) * (1.0 - 0.2 * f * v)


def pd_like(u: np.ndarray) -> np.ndarray:
    """Another smooth function, range about 0.45-0.67."""
    f, d, h, v = u.T
    return 0.62 - 0.12 * f**1.5 - 0.06 * np.tanh(2.0 * (d - h)) - 0.04 * v * v + 0.03 * f * d


def results_table(n: int = N_CASES, seed: int = 7, bad: dict | None = None) -> pd.DataFrame:
    """A results table in the package convention, from scrambled Halton points."""
    u = qmc.Halton(d=4, scramble=True, seed=seed).random(n)
    df = pd.DataFrame(design.to_physical(u), columns=list(design.NAMES))
    df.insert(0, "index", np.arange(n))
    df.insert(0, "sweep", "lds")
    df.insert(0, "case_id", [f"lds-{i:05d}" for i in range(n)])
    df["preset"] = "test"
    df["status"] = "ok"
    df["mfr"] = mfr_like(u)
    df["pd"] = pd_like(u)
    df["regime"] = "normal"
    df["flagged"] = False
    df["flag_reason"] = ""
    for reason, idx in (bad or {}).items():
        if reason in ("failed", "blown"):
            df.loc[idx, "status"] = reason
            df.loc[idx, ["mfr", "pd"]] = np.nan
            df.loc[idx, "regime"] = ""
        elif reason == "flagged":
            df.loc[idx, "flagged"] = True
            df.loc[idx, "flag_reason"] = "peak overlap above bound"
        elif reason == "nonfinite":
            df.loc[idx, "pd"] = np.nan
    return df


@pytest.fixture(scope="module")
def table():
    return results_table(bad=BAD)


@pytest.fixture(scope="module")
def result(table):
    return S.fit_surrogate(table, FAST)


@pytest.fixture(scope="module")
def saved(result, tmp_path_factory):
    path = tmp_path_factory.mktemp("model") / "surrogate.joblib"
    S.save_model(result.model, path)
    return path


def centre() -> dict:
    return {p.name: (p.low + p.high) / 2 for p in design.PARAMETERS}


# ---------------------------------------------------------------------------------------------
# training rows and split
# ---------------------------------------------------------------------------------------------
def test_excluded_rows_are_counted_not_dropped_silently(table, result):
    usable, excl = S.select_training_rows(table)
    assert excl == {"failed": 3, "blown": 2, "flagged": 4, "nonfinite": 1}
    assert len(usable) == N_CASES - 10
    bad_ids = {f"lds-{i:05d}" for idx in BAD.values() for i in idx}
    assert not bad_ids & set(usable["case_id"])
    assert result.exclusions == excl
    assert result.model.metadata["exclusions"] == excl
    assert not bad_ids & set(result.split["case_id"])
    assert result.n_train + result.n_test == N_CASES - 10


def test_flagged_column_read_from_csv_strings(table, tmp_path):
    p = tmp_path / "results.csv"
    table.to_csv(p, index=False)
    back = pd.read_csv(p, keep_default_na=True)
    back["flagged"] = back["flagged"].map({True: "True", False: "False"})
    _, excl = S.select_training_rows(back)
    assert excl["flagged"] == 4
    back.loc[0, "flagged"] = "maybe"
    with pytest.raises(ValueError, match="flagged"):
        S.select_training_rows(back)


def test_bad_tables_refused(table):
    with pytest.raises(ValueError, match="lacks column"):
        S.select_training_rows(table.drop(columns=["flagged"]))
    dup = pd.concat([table, table.iloc[[5]]], ignore_index=True)
    with pytest.raises(ValueError, match="duplicate case_id"):
        S.select_training_rows(dup)
    with pytest.raises(ValueError, match="too few usable cases"):
        S.fit_surrogate(table.iloc[:6], FAST)
    with pytest.raises(ValueError, match="unknown surrogate config"):
        S.make_config({"neuron": [8]})


def test_split_identical_across_partitions():
    big = results_table(n=1200, seed=3)
    full = S.partition(big, 1200)
    mask_full = S.test_mask(full["case_id"], 0.2, seed=0)
    for n1 in (10, 50, 137, 500, 1000):
        part = S.partition(big, n1)
        assert list(part["index"]) == list(range(n1))
        mask = S.test_mask(part["case_id"], 0.2, seed=0)
        # the test set of N1 is the test set of N2 restricted to the first N1 cases
        assert np.array_equal(mask, mask_full[:n1])
    # independent of row order (a function of the case identity only)
    shuffled = full.sample(frac=1.0, random_state=1)
    m2 = pd.Series(S.test_mask(shuffled["case_id"], 0.2, 0), index=shuffled["case_id"])
    assert np.array_equal(m2.loc[full["case_id"]].to_numpy(), mask_full)
    # about 20 %, and a different seed gives a different split
    assert 0.17 < mask_full.mean() < 0.23
    assert not np.array_equal(S.test_mask(full["case_id"], 0.2, seed=1), mask_full)
    # with test_fraction = 1/k, CV fold 0 is the held-out set
    assert np.array_equal(S.fold_of(full["case_id"], 5, 0) == 0, mask_full)


# ---------------------------------------------------------------------------------------------
# accuracy on known smooth functions
# ---------------------------------------------------------------------------------------------
def test_mlp_and_gp_reach_r2_above_099(result):
    s = result.summary
    for t in design.TARGETS:
        st = s[s["target"] == t]
        chosen = st[st["chosen"]].iloc[0]
        assert chosen["r2_mean"] == st["r2_mean"].max()
        assert chosen["r2_mean"] > 0.99 and chosen["r2_min"] > 0.99
        assert result.ensemble_r2[t] > 0.99
        gp = result.gp.set_index("target").loc[t]
        assert gp["r2_test"] > 0.99 and gp["cv_r2_mean"] > 0.99
        assert chosen["cv_r2_mean"] > 0.99 and np.isfinite(chosen["cv_r2_std"])
        fit = result.parity_fit.set_index("target").loc[t]
        assert abs(fit["slope"] - 1.0) < 0.03 and abs(fit["intercept"]) < 0.02
        assert fit["n"] == result.n_test
    runs = result.runs
    assert len(runs) == len(FAST["neurons"]) * len(FAST["seeds"]) * 2
    assert runs["converged"].all()
    print("\nR2 summary\n", S.metrics_table(result).to_string())


def test_parity_and_learning_curve_tables(result):
    par = result.parity
    assert set(par["target"]) == set(design.TARGETS)
    test_ids = set(result.split.loc[result.split["is_test"], "case_id"])
    assert set(par["case_id"]) == test_ids
    assert (par["predicted_std"] >= 0).all() and (par["predicted_std"] > 0).any()
    lc = result.learning
    assert sorted(lc["n_cases"].unique()) == [50, 100, N_CASES]
    assert (lc["n_test"] == result.n_test).all()
    for t in design.TARGETS:
        lt = lc[lc["target"] == t].sort_values("n_cases")
        assert lt["n_train"].is_monotonic_increasing
        assert lt["r2_mean"].iloc[-1] > 0.99
        assert lt["gp_r2"].iloc[-1] > 0.99
        # the largest prefix is the full training set: the sweep's and the baseline's fits
        ch = result.summary[(result.summary["target"] == t) & result.summary["chosen"]].iloc[0]
        assert lt["r2_mean"].iloc[-1] == ch["r2_mean"]
        assert lt["gp_r2"].iloc[-1] == result.gp.set_index("target").loc[t, "r2_test"]
        # fewer cases, a worse (or equal) surrogate on the same held-out cases
        assert lt["r2_mean"].iloc[0] <= lt["r2_mean"].iloc[-1]


def test_metrics_table(result, tmp_path):
    tab = S.metrics_table(result, tmp_path / "m.csv")
    assert (tmp_path / "m.csv").is_file()
    for col in ("target", "model", "neurons", "r2_mean", "r2_min", "r2_max", "cv_r2_mean", "cv_r2_std"):
        assert col in tab.columns
    assert set(tab["model"]) == {"mlp", "mlp_ensemble", "gp"}
    assert len(tab[tab["model"] == "mlp"]) == 2 * len(FAST["neurons"])
    assert (tab["r2_min"] <= tab["r2_mean"] + 1e-15).all() and (tab["r2_mean"] <= tab["r2_max"] + 1e-15).all()


def test_fixed_seeds_reproduce_exactly(table, result):
    cfg = dict(neurons=[6], seeds=[0, 1], gp=False, learning_curve=None, cv_folds=3, ensemble_members=2)
    part = S.partition(table, 120)
    a = S.fit_surrogate(part, cfg)
    b = S.fit_surrogate(part, cfg)
    assert a.runs["r2_test"].tolist() == b.runs["r2_test"].tolist()  # to the last digit
    assert a.cv["r2"].tolist() == b.cv["r2"].tolist()
    assert a.ensemble_r2 == b.ensemble_r2
    X = table[list(design.NAMES)].to_numpy()[:30]
    assert np.array_equal(a.model(X), b.model(X))
    # the partition's test cases are the full table's test cases restricted to index < 120
    full_test = set(result.split.loc[result.split["is_test"], "case_id"])
    first = set(part["case_id"])
    assert set(a.split.loc[a.split["is_test"], "case_id"]) == full_test & first


def test_final_fit_on_all_rows_with_bootstrap(table):
    cfg = dict(neurons=[6], seeds=[0, 1], gp=False, learning_curve=None, cv_folds=2,
               ensemble_members=3, bootstrap=True, final_fit="all")
    part = S.partition(table, 90)
    r = S.fit_surrogate(part, cfg)
    usable, _ = S.select_training_rows(part)
    meta = r.model.metadata
    assert meta["n_fit"] == meta["n_usable"] == len(usable)
    assert meta["training_rows_sha256"] == meta["usable_rows_sha256"] == S.sha256_rows(usable)
    assert meta["training_ranges"]["d_um"] == [usable["d_um"].min(), usable["d_um"].max()]
    assert len(r.model.members["mfr"]) == 3 and meta["member_seeds"] == [0, 1, 2]
    out = S.predict(r.model, usable[list(design.NAMES)])
    assert np.isfinite(out[["mfr", "mfr_std", "pd", "pd_std"]].to_numpy()).all()
    assert (out["mfr_std"] > 0).all()
    assert r.ensemble_r2["mfr"] > 0.95


def test_solver_options_passed_through():
    est = S.make_mlp(8, 3, S.make_config({"solver": "adam", "early_stopping": True, "scaler": "minmax"}))
    mlp = est.regressor[-1]
    assert mlp.solver == "adam" and mlp.early_stopping is True and mlp.hidden_layer_sizes == (8,)
    assert mlp.random_state == 3 and type(est.transformer).__name__ == "MinMaxScaler"
    lb = S.make_mlp(8, 0, S.make_config()).regressor[-1]
    assert lb.solver == "lbfgs" and lb.activation == "tanh" and lb.early_stopping is False


# ---------------------------------------------------------------------------------------------
# prediction
# ---------------------------------------------------------------------------------------------
def test_predict_in_range(result):
    model = result.model
    pts = pd.DataFrame([centre(), {"f": 0.2, "d_um": 20.0, "h_um": 70.0, "v_mm_s": 6.0}])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning for in-range points
        out = S.predict(model, pts)
    for col in ("mfr", "mfr_std", "pd", "pd_std", "outside_training_range"):
        assert col in out.columns
    assert not out["outside_training_range"].any()
    u = design.to_unit(pts[list(design.NAMES)].to_numpy())
    assert np.allclose(out["mfr"], mfr_like(u), atol=0.01)
    assert np.allclose(out["pd"], pd_like(u), atol=0.01)
    assert (out["mfr_std"] >= 0).all() and (out["pd_std"] >= 0).all()
    # column order does not matter; arrays, single points and mappings are accepted
    same = S.predict(model, pts[list(reversed(design.NAMES))])
    assert np.array_equal(same[["mfr", "pd"]].to_numpy(), out[["mfr", "pd"]].to_numpy())
    assert np.array_equal(model(pts[list(design.NAMES)].to_numpy()), out[["mfr", "pd"]].to_numpy())
    # (a single point may differ from the same point in a batch in the last bit: BLAS paths)
    one = S.predict(model, [centre()[n] for n in design.NAMES])
    assert one["mfr"].iloc[0] == pytest.approx(out["mfr"].iloc[0], rel=1e-12)
    assert S.predict(model, centre())["pd"].iloc[0] == pytest.approx(out["pd"].iloc[0], rel=1e-12)


def test_predict_out_of_range_warns_and_flags(result):
    pts = pd.DataFrame([centre(), {**centre(), "f": 0.9}, {**centre(), "v_mm_s": 1.0}])
    with pytest.warns(S.OutOfRangeWarning) as rec:
        out = S.predict(result.model, pts)
    assert out["outside_training_range"].tolist() == [False, True, True]
    assert out["outside_parameters"].tolist() == ["", "f", "v_mm_s"]
    assert np.isfinite(out[["mfr", "pd"]].to_numpy()).all()  # extrapolated, but flagged
    msgs = [str(w.message) for w in rec]
    lo, hi = result.model.metadata["training_ranges"]["f"]
    f_msg = [m for m in msgs if "range of f " in m]
    assert len(f_msg) == 1 and "f = 0.9" in f_msg[0] and f"{lo:.6g}" in f_msg[0] and f"{hi:.6g}" in f_msg[0]
    assert any("v_mm_s = 1" in m for m in msgs)


@pytest.mark.parametrize("points, match", [
    ([[0.3, 30.0, 60.0, np.nan]], "non-finite value nan for parameter 'v_mm_s'"),
    ({"f": [0.3], "d_um": [np.inf], "h_um": [60.0], "v_mm_s": [8.0]}, "non-finite"),
    ([[0.3, 30.0, 60.0]], "4 columns"),
    ([[[0.3, 30.0, 60.0, 8.0]]], "4 columns"),
    (np.zeros((2, 5)), "4 columns"),
    ([[0.3, "thirty", 60.0, 8.0]], "'d_um' must be numeric"),
    ([[0.3, 30.0, None, 8.0]], "'h_um' must be numeric"),
    ([[True, 30.0, 60.0, 8.0]], "'f' must be numeric"),
    ([[0.3, 30.0, 60.0, 8.0], [0.3, 30.0]], "not a rectangular table"),
    ("f=0.3", "string"),
    (pd.DataFrame({"f": ["0.3"], "d_um": [30.0], "h_um": [60.0], "v_mm_s": [8.0]}), "'f' must be numeric"),
    (pd.DataFrame({"f": [True], "d_um": [30.0], "h_um": [60.0], "v_mm_s": [8.0]}), "'f' must be numeric"),
    (pd.DataFrame({"f": [0.3], "d_um": [30.0], "h_um": [60.0]}), r"missing column\(s\) \['v_mm_s'\]"),
    (pd.DataFrame({"f": [0.3], "d_um": [30.0], "h_um": [60.0], "v_mm_s": [8.0], "speed": [1.0]}),
     r"unknown column\(s\) \['speed'\]"),
    ({"f": 0.3, "d": 30.0, "h_um": 60.0, "v_mm_s": 8.0}, r"unknown column\(s\) \['d'\]"),
    (np.empty((0, 4)), "no points"),
])
def test_predict_refuses_malformed_input(result, points, match):
    out = None
    with pytest.raises(ValueError, match=match):
        out = S.predict(result.model, points)
    assert out is None


# ---------------------------------------------------------------------------------------------
# save / load
# ---------------------------------------------------------------------------------------------
def test_save_load_round_trip(result, saved, table):
    model = S.load_model(saved)
    X = table[list(design.NAMES)].to_numpy()
    assert np.array_equal(model(X), result.model(X))
    a, b = S.predict(model, X), S.predict(result.model, X)
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    meta = json.loads(S.sidecar_path(saved).read_text())
    assert meta == model.metadata
    train_ids = set(result.split.loc[~result.split["is_test"], "case_id"])
    usable, _ = S.select_training_rows(table)
    train_rows = usable[usable["case_id"].isin(train_ids)]
    assert meta["training_rows_sha256"] == hashlib.sha256(S.canonical_csv(train_rows)).hexdigest()
    assert meta["training_rows_sha256"] == S.sha256_rows(train_rows.sample(frac=1.0, random_state=0))
    assert len(meta["training_rows_sha256"]) == 64
    assert set(meta["versions"]) >= {"python", "numpy", "sklearn"}
    assert meta["versions"]["sklearn"] == __import__("sklearn").__version__
    assert meta["config_passed"]["neurons"] == FAST["neurons"]
    assert meta["config"]["solver"] == "lbfgs"
    assert meta["neurons"] == result.chosen
    for n in design.NAMES:
        lo, hi = meta["training_ranges"][n]
        assert lo == train_rows[n].min() and hi == train_rows[n].max()
    for t in design.TARGETS:
        assert meta["test_r2"][t]["ensemble"] == result.ensemble_r2[t]
    assert meta["exclusions"]["flagged"] == 4
    with pytest.raises(FileNotFoundError):
        S.load_model(saved.with_name("missing.joblib"))


def test_load_warns_on_other_sklearn_version(result, tmp_path):
    import copy

    model = copy.deepcopy(result.model)
    model.metadata["versions"]["sklearn"] = "0.0.1"
    path, side = S.save_model(model, tmp_path / "old.joblib")
    assert side == tmp_path / "old.json"
    with pytest.warns(UserWarning, match="scikit-learn 0.0.1"):
        S.load_model(path)


# ---------------------------------------------------------------------------------------------
# command line and Snakemake entry
# ---------------------------------------------------------------------------------------------
def run_cli(*args):
    return subprocess.run([PYTHON, str(SCRIPT), *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)


def test_cli_points_and_out_of_range_warning(saved, tmp_path):
    out_csv = tmp_path / "pred.csv"
    r = run_cli(saved, "--point", "f=0.3", "d_um=30", "h_um=60", "v_mm_s=8",
                "--point", "f=0.9", "d_um=30", "h_um=60", "v_mm_s=8", "--out", out_csv)
    assert r.returncode == 0, r.stderr
    assert "mfr_std" in r.stdout and "outside_training_range" in r.stdout
    assert "warning:" in r.stderr and "range of f" in r.stderr and "f = 0.9" in r.stderr
    pred = pd.read_csv(out_csv)
    assert pred["outside_training_range"].tolist() == [False, True]
    assert np.isfinite(pred[["mfr", "mfr_std", "pd", "pd_std"]].to_numpy()).all()


def test_cli_refuses_malformed_csv(saved, tmp_path):
    bad = tmp_path / "bad.csv"
    pd.DataFrame({"f": [0.3, np.nan], "d_um": [30, 30], "h_um": [60, 60], "v_mm_s": [8, 8]}).to_csv(bad, index=False)
    r = run_cli(saved, "--csv", bad)
    assert r.returncode != 0
    assert "non-finite" in r.stderr and "'f'" in r.stderr
    assert r.stdout == ""


@pytest.mark.parametrize("args, match", [
    (["--point", "f=0.3", "d_um=30", "h_um=60"], "lacks parameter"),
    (["--point", "f=0.3", "d_um=abc", "h_um=60", "v_mm_s=8"], "not a number"),
    (["--point", "f=0.3", "d=30", "h_um=60", "v_mm_s=8"], "unknown parameter 'd'"),
    (["--point", "f=nan", "d_um=30", "h_um=60", "v_mm_s=8"], "not finite"),
    ([], "no points"),
])
def test_cli_main_malformed_points(saved, capsys, args, match):
    code = S.cli_main([str(saved), *args])
    cap = capsys.readouterr()
    assert code != 0
    assert match in cap.err
    assert cap.out == ""


def test_cli_csv_with_unknown_column(saved, tmp_path, capsys):
    p = tmp_path / "pts.csv"
    pd.DataFrame({"f": [0.3], "d_um": [30], "h_um": [60], "v_mm_s": [8], "rpm": [1]}).to_csv(p, index=False)
    assert S.cli_main([str(saved), "--csv", str(p)]) == 2
    assert "unknown column(s) ['rpm']" in capsys.readouterr().err


def test_script_under_snakemake(saved, tmp_path, capsys):
    pts = tmp_path / "points.csv"
    pd.DataFrame([centre(), {**centre(), "d_um": 80.0}]).to_csv(pts, index=False)
    out, log = tmp_path / "out" / "pred.csv", tmp_path / "pred.log"
    smk = SimpleNamespace(
        input=SimpleNamespace(model=str(saved), points=str(pts)), output=[str(out)], log=[str(log)],
        params=SimpleNamespace(points=["f=0.2 d_um=20 h_um=60 v_mm_s=10", {"f": 0.4, "d_um": 40, "h_um": 70, "v_mm_s": 12}]))
    runpy.run_path(str(SCRIPT), init_globals={"snakemake": smk}, run_name="__main__")
    pred = pd.read_csv(out)
    assert len(pred) == 4
    assert pred["outside_training_range"].tolist() == [False, True, False, False]
    assert "range of d_um" in log.read_text() and "range of d_um" in capsys.readouterr().err
    smk.params = SimpleNamespace(points=["f=0.2 d_um=20 h_um=60"])
    with pytest.raises(ValueError, match="lacks parameter"):
        runpy.run_path(str(SCRIPT), init_globals={"snakemake": smk}, run_name="__main__")


# ---------------------------------------------------------------------------------------------
# figures
# ---------------------------------------------------------------------------------------------
def test_plots_written_with_data(result, tmp_path):
    files = SP.plot_all(result, tmp_path)
    for name in ("parity", "r2_vs_neurons", "learning_curve"):
        stem = tmp_path / f"surrogate_{name}"
        for suffix in (".png", ".pdf", ".csv"):
            f = stem.with_name(stem.name + suffix)
            assert f in files[name] and f.stat().st_size > 0
    assert (tmp_path / "surrogate_parity_fit.csv").is_file()
    assert (tmp_path / "surrogate_metrics.csv").is_file()
    par = pd.read_csv(tmp_path / "surrogate_parity.csv")
    assert set(par.columns) >= {"target", "case_id", "dem", "predicted", "predicted_std"}
    assert (tmp_path / "surrogate_parity.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "surrogate_parity.pdf").read_bytes()[:4] == b"%PDF"
