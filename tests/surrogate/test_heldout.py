"""The held-out check (spreadlab.heldout_points) on synthetic studies whose truth, model error
and run noise are known."""
import numpy as np
import pandas as pd
import pytest

from spreadlab.heldout_points import choose_points, score
from spreadmap.design import NAMES, to_unit

RANGES = {"f": {"min": 0.15, "max": 0.45}, "d_um": {"min": 10, "max": 50}, "h_um": {"min": 55, "max": 75},
          "v_mm_s": {"min": 5, "max": 15}}


def test_chosen_points_are_in_range_far_from_the_runs_and_from_one_another():
    rng = np.random.default_rng(3)
    ran = pd.DataFrame({k: rng.uniform(r["min"], r["max"], 40) for k, r in RANGES.items()})
    pts = choose_points(12, RANGES, ran, min_distance=0.2, seed=5)
    u, v = to_unit(pts[list(NAMES)].to_numpy(float), RANGES), to_unit(ran[list(NAMES)].to_numpy(float), RANGES)
    assert len(pts) == 12 and list(pts["name"])[:2] == ["heldout_01", "heldout_02"]
    assert ((u >= 0) & (u <= 1)).all()
    assert np.min(np.linalg.norm(u[:, None, :] - v[None, :, :], axis=2)) >= 0.2
    pair = np.linalg.norm(u[:, None, :] - u[None, :, :], axis=2) + np.eye(12) * 9
    assert pair.min() >= 0.2
    # reproducible from its seed, another seed another set
    assert choose_points(12, RANGES, ran, 0.2, seed=5).equals(pts)
    assert not choose_points(12, RANGES, ran, 0.2, seed=6).equals(pts)
    # a second check names its points apart from the first's
    assert list(choose_points(2, RANGES, ran, 0.2, seed=5, prefix="heldout2")["name"]) == ["heldout2_01", "heldout2_02"]


def test_too_crowded_a_space_is_refused_with_the_knob_to_turn():
    ran = pd.DataFrame({k: np.linspace(r["min"], r["max"], 5) for k, r in RANGES.items()})
    with pytest.raises(ValueError, match="lower min_distance"):
        choose_points(12, RANGES, ran, min_distance=0.9)


def synthetic(rng, n_points, seeds, model_sd, noise_sd, stated_model_sd):
    """Predictions off the truth by N(0, model_sd); runs = truth + N(0, noise_sd); the
    predictions state stated_model_sd and the right noise."""
    names = [f"p{i}" for i in range(n_points)]
    truth = rng.uniform(0.2, 0.5, n_points)
    pred = truth + rng.normal(0, model_sd, n_points)
    predictions = pd.DataFrame({"name": names, "mfr": pred, "mfr_model_sd": stated_model_sd,
                                "mfr_run_sd": np.sqrt(stated_model_sd ** 2 + noise_sd ** 2)})
    cases = pd.DataFrame({"name": np.repeat(names, seeds),
                          "mfr": np.repeat(truth, seeds) + rng.normal(0, noise_sd, n_points * seeds)})
    return predictions, cases


def test_right_intervals_cover_at_their_level_and_pass_the_sd_test():
    rng = np.random.default_rng(11)
    inside = total = 0
    p_values = []
    for _ in range(200):
        pred, cases = synthetic(rng, 12, 4, 0.02, 0.03, 0.02)
        _, s = score(pred, cases, "mfr")
        inside, total = inside + s["inside"], total + s["points"]
        p_values.append(s["p_sd_right"])
    assert inside / total == pytest.approx(0.95, abs=0.015)  # 2400 points: SE 0.0045
    assert np.mean(np.array(p_values) < 0.05) == pytest.approx(0.05, abs=0.035)


def test_overconfident_intervals_are_caught():
    rng = np.random.default_rng(12)
    pred, cases = synthetic(rng, 40, 4, 0.06, 0.03, 0.01)  # the model claims 0.01, is off by 0.06
    table, s = score(pred, cases, "mfr")
    assert s["coverage_high"] < 0.95 and s["p_sd_right"] < 1e-3 and s["p_sd_too_wide"] > 0.999
    assert s["rmse"] > 2 * s["rmse_expected"]
    # the seed mean of 4 runs: SD sqrt(0.01^2 + 0.03^2 / 4)
    assert table["sd_of_mean"].iloc[0] == pytest.approx(np.sqrt(0.01 ** 2 + 0.03 ** 2 / 4))
    assert (table["n_runs"] == 4).all()


def test_underconfident_intervals_are_caught_by_the_other_tail():
    """A model right to 0.002 that states 0.03, with runs of noise 0.01 stated as 0.03: every point
    inside, and the lower tail of the chi-square test says the SDs are too large."""
    rng = np.random.default_rng(14)
    pred, cases = synthetic(rng, 12, 4, 0.002, 0.01, 0.03)
    pred["mfr_run_sd"] = np.sqrt(0.03 ** 2 + 0.03 ** 2)
    _, s = score(pred, cases, "mfr")
    assert s["inside"] == 12 and s["mean_z2"] < 0.2
    assert s["p_sd_too_wide"] < 1e-3 and s["p_sd_right"] > 0.999
    assert s["p_sd_right"] + s["p_sd_too_wide"] == pytest.approx(1.0)


def test_points_without_runs_are_left_out_and_none_at_all_is_an_error():
    rng = np.random.default_rng(13)
    pred, cases = synthetic(rng, 5, 3, 0.02, 0.03, 0.02)
    table, s = score(pred, cases[cases["name"] != "p0"], "mfr")
    assert s["points"] == 4 and "p0" not in set(table["name"])
    with pytest.raises(ValueError, match="no held-out point"):
        score(pred, cases.iloc[0:0], "mfr")


def test_the_cli_chooses_predicts_and_scores_held_out_runs_of_a_known_truth(tmp_path):
    """End to end on a synthetic study (tests/synthetic_cases.py): a surrogate fitted on 48 noisy
    cases and saved; `choose` writes 12 points x 4 seeds away from them and their predictions;
    runs drawn from the truth with the known noise (one flagged, left out) are scored by `score`.
    The GP's intervals on this smooth truth should hold most seed means; the test asks >= 9 of 12
    (a 95 % interval misses 3 or more of 12 with probability 0.02)."""
    import json
    import subprocess
    import sys

    import synthetic_cases as syn
    from conftest import ROOT

    from spreadmap.surrogate import fitting, saved_model

    train = syn.table(48, 0.07, seed=1)
    quick = {"cv_repeats": 1, "gp_restarts": 0, "learning_curve": False, "mlp_sizes": [4], "mlp_alphas": [1.0],
             "ensemble_members": 4, "neurons": [2, 4], "seeds": [0, 1, 2]}
    model = tmp_path / "model.joblib"
    saved_model.save_model(fitting.fit_surrogate(train, quick, log=lambda *a: None).model, model)
    ran = tmp_path / "ran.csv"
    train.to_csv(ran, index=False)
    points, predictions = tmp_path / "points.csv", tmp_path / "pred.csv"
    script = [sys.executable, str(ROOT / "tools" / "heldout.py")]
    r = subprocess.run([*script, "choose", "--model", str(model), "--ran", str(ran), "--points", str(points),
                        "--predictions", str(predictions), "--min-distance", "0.1"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    runs = pd.read_csv(points)
    assert len(runs) == 48 and set(runs["seed"]) == {1, 2, 3, 4} and runs["name"].nunique() == 12
    assert (runs["preset"] == "default").all()
    rng = np.random.default_rng(21)
    X = runs[list(NAMES)].to_numpy(float)
    table = runs[list(NAMES) + ["seed"]].copy()
    table["status"], table["flagged"] = "ok", False
    for t in ("mfr", "pd"):
        table[t] = syn.TRUTH[t](X) + rng.normal(0, syn.noise_sd(X, t, 0.07))
    table.loc[0, "flagged"] = True  # a flagged run is not scored
    table.to_csv(tmp_path / "table.csv", index=False)
    out = tmp_path / "heldout" / "score.csv"  # where a study keeps it (tools/publish_study.py copies heldout/)
    out.parent.mkdir()
    r = subprocess.run([*script, "score", "--points", str(points), "--predictions", str(predictions),
                        "--table", str(tmp_path / "table.csv"), "--out", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    scored = pd.read_csv(out)
    summary = json.loads(out.with_suffix(".json").read_text())
    assert [s["target"] for s in summary] == ["mfr", "pd"] and all(s["points"] == 12 for s in summary)
    assert scored["n_runs"].sum() == 2 * 47  # 48 runs less the flagged one, per target
    assert all(s["inside"] >= 9 for s in summary), summary
    assert "seed means inside their 95% intervals" in r.stdout
    # the study's summary states the check from these files, and names every point outside
    from spreadlab.study.summary import summary_markdown, trends

    text = summary_markdown(tmp_path, trends(tmp_path))
    for t in ("mfr", "pd"):
        inside = int(scored.loc[scored["target"] == t, "inside"].sum())
        assert f"- {t}: {inside} of 12 points' seed means inside their 95 % prediction intervals" in text
    outside = [line for line in text.splitlines() if line.startswith("  - outside: ")]
    assert len(outside) == int((~scored["inside"]).sum())
    # a missing file is one line, status 2
    r = subprocess.run([*script, "score", "--points", str(tmp_path / "none.csv"), "--predictions", str(predictions),
                        "--table", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and r.stderr.startswith("heldout.py: error: file not found") and r.stderr.count("\n") == 1
    # the figure: one label per score, the numbers behind it are the scored rows with their check
    r = subprocess.run([*script, "plot", "--scores", str(out), "--labels", "a", "b", "--out", str(tmp_path / "fig")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "--labels: 2 given for 1 --scores" in r.stderr
    r = subprocess.run([*script, "plot", "--scores", str(out), str(out), "--labels", "first", "again",
                        "--out", str(tmp_path / "fig")], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "fig.png").stat().st_size > 10_000 and (tmp_path / "fig.pdf").exists()
    behind = pd.read_csv(tmp_path / "fig.csv")
    assert len(behind) == 2 * len(scored) and list(behind["check"].unique()) == ["first", "again"]
    np.testing.assert_allclose(behind.loc[behind["check"] == "first", "z"], scored["z"])
