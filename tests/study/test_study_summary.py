"""The study's summary (spreadlab.study.summary): partial dependence against functions of known
effect, and the answers it writes from a study folder's files (analysis code: synthetic inputs)."""
import json

import numpy as np
import pandas as pd

from spreadlab.study.summary import NOT_YET, main_effect, summary_markdown, trends
from spreadmap.design import NAMES
from spreadmap.sensitivity.draws import FunctionDraws

RANGES = {"f": {"min": 0.15, "max": 0.45}, "d_um": {"min": 10, "max": 50}, "h_um": {"min": 55, "max": 75},
          "v_mm_s": {"min": 5, "max": 15}}
F, D, H, V = (NAMES.index(n) for n in ("f", "d_um", "h_um", "v_mm_s"))


def summary(study, ranges=None) -> str:
    """The study's summary.md as tools/publish_study.py makes it: the trends, then the text."""
    return summary_markdown(study, trends(study, ranges))


def known(X):
    """mfr: linear in v plus a friction term that averages to zero over f's range; pd: 0.05 h/d."""
    mfr = 0.02 * X[:, V] + 0.1 * np.sin(2 * np.pi * (X[:, F] - 0.15) / 0.30)
    return np.column_stack([mfr, 0.05 * X[:, H] / X[:, D]])


def test_partial_dependence_recovers_known_effects():
    model = FunctionDraws(known, ("mfr", "pd"))
    v = main_effect(model, RANGES, "v_mm_s", [5, 10, 15], n_base=256)
    np.testing.assert_allclose(v["mfr"], [0.1, 0.2, 0.3], atol=2e-3)  # the sine averages out
    hd = main_effect(model, RANGES, "h_over_d", [1.2, 3.0, 7.0], n_base=256)
    np.testing.assert_allclose(hd["pd"], [0.06, 0.15, 0.35], rtol=1e-12)  # h = level x d exactly
    # the points where h = level x d lies in [55, 75] um: d in [55 / level, 75 / level] within [10, 50]
    for level, n in zip(hd["level"], hd["n_points"]):
        share = (min(50, 75 / level) - max(10, 55 / level)) / 40
        assert abs(n / 256 - share) < 0.03, (level, n, share)
    f = main_effect(model, RANGES, "f", [0.15, 0.225, 0.30])
    np.testing.assert_allclose(f["mfr"] - f["mfr"].iloc[0], [0.0, 0.1, 0.0], atol=1e-9)  # sin(0), sin(pi/2), sin(pi)
    # a known function has no model uncertainty: the band collapses onto the effect
    np.testing.assert_allclose(f["mfr_low"], f["mfr"], atol=1e-12)
    np.testing.assert_allclose(f["mfr_high"], f["mfr"], atol=1e-12)


def test_the_trends_section_is_drawn_from_the_effects_it_is_given(tmp_path):
    """The summary renders the trends it is handed (the ends of each effect, targets in their
    order); trends() of a folder without a surrogate is empty, and the section says not yet."""
    model = FunctionDraws(known, ("mfr", "pd"))
    effects = {"v_mm_s": main_effect(model, RANGES, "v_mm_s", [5, 10, 15], n_base=256)}
    lines = summary_markdown(tmp_path, effects).splitlines()
    mfr, pd_ = (next(x for x in lines if x.startswith(f"- {t} vs v_mm_s: ")) for t in ("mfr", "pd"))
    assert lines.index(mfr) < lines.index(pd_)
    a, b = effects["v_mm_s"].iloc[0], effects["v_mm_s"].iloc[-1]
    assert mfr == (f"- mfr vs v_mm_s: {a['mfr']:.3f} ({a['mfr_low']:.3f}-{a['mfr_high']:.3f}) at 5 to "
                   f"{b['mfr']:.3f} ({b['mfr_low']:.3f}-{b['mfr_high']:.3f}) at 15")
    assert trends(tmp_path, RANGES) == {}
    assert "partial dependence, 95 % bands)\n" + NOT_YET in summary_markdown(tmp_path, {})
    assert not list(tmp_path.iterdir())  # the summary writes nothing


def test_the_summary_answers_from_the_files_and_says_what_has_not_run(tmp_path):
    pd.DataFrame([{"sweep": "lds", "planned": 81, "finished": 40, "ok": 39, "failed": 1, "cpu_hours": 1.25}]).to_csv(
        tmp_path / "progress.csv", index=False)
    (tmp_path / "converge").mkdir()
    (tmp_path / "converge" / "stopped.json").write_text(json.dumps(
        {"n": 96, "usable": 90, "cpu_hours": 3.5, "reason": "all criteria held", "criteria": {"criteria_met": True}}))
    (tmp_path / "maps").mkdir()
    pd.DataFrame([{"target": "mfr", "parameter": "d_um", "ST": 0.8, "ST_low": 0.7, "ST_high": 0.9, "rank_ST": "1"},
                  {"target": "mfr", "parameter": "v_mm_s", "ST": 0.1, "ST_low": 0.02, "ST_high": 0.2, "rank_ST": "2-3"},
                  {"target": "mfr", "parameter": "f", "ST": 0.12, "ST_low": 0.05, "ST_high": 0.2, "rank_ST": "2-3"}]
                 ).to_csv(tmp_path / "maps" / "sensitivity_ranking_table.csv", index=False)
    reasons = ["flow fell by 15% over the window (-4.6 SE): the pile ran down", "", ""]
    pd.DataFrame([{"case_id": f"c{i}", "status": "ok", "regime": r, "h_um": 55.0, "d_um": d, "v_mm_s": v, "flagged": i == 0,
                   "flag_reason": reasons[i]}
                  for i, (r, d, v) in enumerate([("jamming", 50, 5), ("jamming", 45, 6), ("normal", 20, 10)])]
                 ).to_csv(tmp_path / "cases_lds.csv", index=False)
    text = summary(tmp_path, RANGES)
    assert "lds: 40 of 81 cases finished (1 failed), 1.25 CPU hours" in text
    assert "the map criteria held at **96 cases**" in text
    assert "The study's rule on the sweeps: " + NOT_YET in text
    mfr = next(line for line in text.splitlines() if line.startswith("- mfr: d_um"))
    assert mfr.index("f 0.12") < mfr.index("v_mm_s 0.10")  # ordered by the total index
    assert "do not separate the ranks 2-3" in mfr
    assert "- jamming: 2 of 3 cases; h/d 1.10-1.22, v 5.0-6.0 mm/s" in text
    assert ("- flagged (kept out of training): 1 of 3 cases: h/d 1.10, d 50 um, v 5.0 mm/s; "
            "why: the pile ran down (1)") in text
    assert text.count(NOT_YET) == 4  # the rule, the surrogate's metrics, the held-out check, the trends


def test_the_studys_rule_so_far_uses_only_complete_partitions(tmp_path):
    """LDS partitions [4, 8, 12] with cases 0-9 finished: only 4 and 8 are complete, and the
    line states the largest change of the five statistics of MFR and PD from 4 to 8, computed here
    with numpy and scipy (std ddof 1, biased skewness and excess kurtosis, floors 1 for those)."""
    import yaml
    from scipy import stats

    rng = np.random.default_rng(1)
    cases = pd.DataFrame({"case_id": [f"c{i}" for i in range(10)], "index": range(10), "mfr": rng.normal(0.4, 0.05, 10),
                          "pd": rng.normal(0.3, 0.04, 10),
                          "status": "ok", "flagged": False, "regime": "normal", "f": 0.3, "d_um": 30.0,
                          "h_um": 65.0, "v_mm_s": 10.0})
    cases.to_csv(tmp_path / "cases_lds.csv", index=False)
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(
        {"sweeps": {"lds": {"partitions": [4, 8, 12]}}, "convergence": {"tolerance": 0.005}}))

    def five(x):
        return {"mean": (np.mean(x), 0.0), "std": (np.std(x, ddof=1), 0.0), "median": (np.median(x), 0.0),
                "skewness": (stats.skew(x), 1.0), "kurtosis": (stats.kurtosis(x), 1.0)}

    change = 0.0
    for t in ("mfr", "pd"):
        a, b = five(cases[t][:4].to_numpy()), five(cases[t][:8].to_numpy())
        change = max(change, *(abs(b[s][0] - a[s][0]) / max(abs(a[s][0]), a[s][1]) for s in a))
    text = summary(tmp_path)
    assert f"largest change at N = 8: {100 * change:.1f} %" in text
    assert "N = 12" not in text and "not within 8 cases" in text


def test_a_loop_still_running_is_reported_from_its_last_step(tmp_path):
    """No stopped.json yet: the summary quotes the last step's own account (steps sorted by their
    number of cases, 112 after 48)."""
    steps = tmp_path / "converge" / "steps"
    steps.mkdir(parents=True)
    for n in (32, 48, 112):
        (steps / f"step_{n}.json").write_text(json.dumps({"n": n, "summary": f"after {n} cases: criteria not met yet"}))
    text = summary(tmp_path)
    assert "still running: 3 steps so far" in text and "after 112 cases: criteria not met yet" in text
    assert "after 48 cases" not in text


def test_the_summary_names_the_floor_of_the_studys_config(tmp_path):
    """The study's config (config.yaml beside its files) names the floor under the title; a study
    folder without one says nothing of a floor."""
    assert "Floor:" not in summary(tmp_path)
    (tmp_path / "config.yaml").write_text("scene:\n  substrate:\n    kind: rough\n    jitter: 0.25\n")
    lines = summary(tmp_path).splitlines()
    assert lines[2] == ("Floor: rough floor (previous layer, jitter 0.25 R); gap h nominal, from its tops "
                        "(effective gap h + 0.23 d).")


def test_flag_causes_are_counted_by_their_cause_with_numbers_hidden():
    from spreadlab.study.summary import _flag_causes

    flagged = pd.DataFrame({"flag_reason": [
        "flow fell by 15% over the window (-4.6 SE): the pile ran down",
        "peak overlap 0.112 R > 0.1 R; flow fell by 18% over the window (-5.8 SE): the pile ran down",
        "peak overlap 0.13 R > 0.1 R", None]})
    assert _flag_causes(flagged) == "; why: the pile ran down (2), peak overlap # R > # R (2)"
    assert _flag_causes(pd.DataFrame({"flag_reason": [""]})) == ""
    # a cause met once keeps its numbers
    once = pd.DataFrame({"flag_reason": ["peak overlap 0.0516 R > 0.05 R", "x fell: the pile ran down"]})
    assert _flag_causes(once) == "; why: peak overlap 0.0516 R > 0.05 R (1), the pile ran down (1)"


def test_the_summary_says_jamming_was_not_reached_and_how_close_the_nearest_case_came(tmp_path):
    (tmp_path / "config.yaml").write_text(json.dumps({"regime": {"jam_mfr_max": 0.05}}))
    pd.DataFrame([{"case_id": f"c{i}", "status": "ok", "regime": "normal", "h_um": h, "d_um": 20.0, "v_mm_s": v,
                   "f": f, "mfr": m, "flagged": False}
                  for i, (h, v, f, m) in enumerate([(40.0, 12.0, 0.4, 0.31), (80.0, 6.0, 0.2, 0.52), (30.0, 9.0, 0.3, 0.1)])]
                 ).to_csv(tmp_path / "cases_lds.csv", index=False)
    cases = pd.read_csv(tmp_path / "cases_lds.csv")
    cases.loc[2, "flagged"] = True  # a flagged case's MFR is not a measurement to quote
    cases.to_csv(tmp_path / "cases_lds.csv", index=False)
    text = summary(tmp_path, RANGES)
    assert ("- jamming: none of 3 cases (the rule: MFR < 0.05); the lowest MFR of a usable case 0.310, at h/d 2.00, "
            "v 12.0 mm/s, f 0.40") in text
    # where jamming was reached the line counts those cases instead
    assert "jamming: none" not in summary(_with_regime(tmp_path, "jamming"), RANGES)


def _with_regime(study, regime):
    cases = pd.read_csv(study / "cases_lds.csv")
    cases.loc[0, "regime"] = regime
    cases.to_csv(study / "cases_lds.csv", index=False)
    return study


def test_the_summary_states_the_map_models_intervals_by_h_over_d(tmp_path):
    (tmp_path / "surrogate").mkdir()
    metrics = {"n_predictions": 4, "n_cases": 4, "rmse": 0.01, "rmse_low": 0.01, "rmse_high": 0.01, "rmse_over_noise": 1.0,
               "noise_sd": 0.01, "level": 0.95, "coverage": 1.0, "coverage_low": 1.0, "coverage_high": 1.0}
    pd.DataFrame([{**metrics, "target": "mfr", "model": "gp", "map_model": True},
                  {**metrics, "target": "mfr", "model": "mlp", "map_model": False}]
                 ).to_csv(tmp_path / "surrogate" / "surrogate_metrics.csv", index=False)
    rows = [{"case_id": c, "target": "mfr", "model": m, "y": 0.5 + e, "mean": 0.5, "run_sd": 0.02, "model_sd": 0.01,
             "case_sd": 0.015} for c, e in (("a", 0.01), ("b", -0.01)) for m in ("gp", "mlp")]
    rows.append({"case_id": "a", "target": "mfr", "model": "mlp", "y": 0.9, "mean": 0.5, "run_sd": 0.02, "model_sd": 0.01,
                 "case_sd": 0.015})  # the other model's prediction: not read
    pd.DataFrame(rows).to_csv(tmp_path / "surrogate" / "surrogate_parity.csv", index=False)
    pd.DataFrame({"case_id": ["a", "b"], "h_um": [60.0, 60.0], "d_um": [40.0, 15.0], "status": "ok", "regime": "normal",
                  "v_mm_s": 10.0, "flagged": False}).to_csv(
        tmp_path / "cases_converge.csv", index=False)
    line = next(x for x in summary(tmp_path, RANGES).splitlines() if x.startswith("- mfr (gp), its intervals"))
    assert ("1.5-2: 1 cases, error 0.0100 against the cases' noise 0.0150, interval SD 0.0200 (the model's 0.0100), "
            "mean z^2 0.25, 100 % inside") in line
    assert ">= 3: 1 cases, error 0.0100" in line and "0-1.5" not in line and "left out" not in line
    # the coverage line says what its interval supports: 100 % (100-100 %) of 95 % intervals is too wide
    line = next(x for x in summary(tmp_path, RANGES).splitlines() if x.startswith("- mfr (gp, the maps): CV RMSE"))
    assert line.endswith("the intervals are too wide (their coverage's CI lies above 95 %)"), line
    # a case of the training table in no published cases table (the main job trains on more): left out, said so
    pd.DataFrame(rows + [{**rows[0], "case_id": "z"}]).to_csv(tmp_path / "surrogate" / "surrogate_parity.csv", index=False)
    line = next(x for x in summary(tmp_path, RANGES).splitlines() if x.startswith("- mfr (gp), its intervals"))
    assert "; 1 cases in no published table left out): " in line and "1.5-2: 1 cases" in line


def test_matched_size_compares_the_lattice_and_the_lds_prefix_with_the_largest_lds_partition(tmp_path):
    """Both samples' five statistics against LDS 256's, by the study's measure; the numbers checked
    against numpy and scipy directly (skewness and kurtosis with floor 1, the others relative)."""
    from scipy import stats

    rng = np.random.default_rng(11)
    lds = pd.DataFrame({"index": np.arange(256), "sweep": "lds", "status": "ok", "flagged": False,
                        "mfr": rng.normal(0.45, 0.05, 256), "pd": rng.normal(0.40, 0.06, 256)})
    lattice = pd.DataFrame({"k": 3, "sweep": "lattice", "status": "ok", "flagged": False,
                            "mfr": np.tile([0.40, 0.45, 0.50], 27), "pd": np.tile([0.30, 0.40, 0.50], 27)})
    for name, table in (("lds", lds), ("lattice", lattice)):
        table.assign(case_id=[f"{name}{i}" for i in range(len(table))], regime="normal", h_um=60.0, d_um=30.0,
                     v_mm_s=10.0).to_csv(tmp_path / f"cases_{name}.csv", index=False)
    (tmp_path / "config.yaml").write_text(json.dumps({"sweeps": {"lds": {"partitions": [81, 256]}, "lattice": {"k": [3, 4]}}}))
    line = next(x for x in summary(tmp_path, RANGES).splitlines() if x.startswith("- Matched size N = 81"))

    def stats5(x):
        return {"mean": np.mean(x), "std": np.std(x, ddof=1), "median": np.median(x),
                "kurtosis": stats.kurtosis(x), "skewness": stats.skew(x)}

    def worst(x, ref):
        a, b = stats5(ref), stats5(x)
        floor = {"kurtosis": 1.0, "skewness": 1.0}
        return max(abs(b[s] - a[s]) / max(abs(a[s]), floor.get(s, 0.0)) for s in a)

    lat = max(worst(lattice[t].to_numpy(), lds[t].to_numpy()) for t in ("mfr", "pd"))
    pre = max(worst(lds[t].to_numpy()[:81], lds[t].to_numpy()) for t in ("mfr", "pd"))
    assert f"the LDS's first 81 by at most {100 * pre:.1f} %" in line
    assert f"the 3^4 lattice by at most {100 * lat:.1f} %" in line
    assert f"mean MFR {np.mean(lds['mfr'][:81]):.4f}, 0.4500, {np.mean(lds['mfr']):.4f}" in line
    assert f"would scatter by {np.std(lds['mfr'], ddof=1) / 9:.4f} and {np.std(lds['pd'], ddof=1) / 9:.4f}" in line
    # the 4^4 lattice has not run: no line for it
    assert "N = 256" not in "".join(x for x in summary(tmp_path, RANGES).splitlines() if x.startswith("- Matched"))
    # once it has: at LDS 256's own size the lattice alone against it, and the study's rule from lattice to lattice
    lattice4 = pd.DataFrame({"k": 4, "sweep": "lattice", "status": "ok", "flagged": False,
                             "mfr": np.tile([0.38, 0.43, 0.47, 0.52], 64), "pd": np.tile([0.32, 0.38, 0.42, 0.48], 64)})
    both = pd.concat([lattice, lattice4], ignore_index=True)
    both.assign(case_id=[f"lattice{i}" for i in range(len(both))], regime="normal", h_um=60.0, d_um=30.0,
                v_mm_s=10.0).to_csv(tmp_path / "cases_lattice.csv", index=False)
    text = summary(tmp_path, RANGES).splitlines()
    line = next(x for x in text if x.startswith("- Matched size N = 256"))
    lat4 = max(worst(lattice4[t].to_numpy(), lds[t].to_numpy()) for t in ("mfr", "pd"))
    assert f"the 4^4 lattice by at most {100 * lat4:.1f} %" in line and "LDS's first" not in line
    assert f"mean MFR {np.mean(lattice4['mfr']):.4f}, {np.mean(lds['mfr']):.4f} and PD" in line
    assert "(lattice, LDS 256; " in line
    rule = next(x for x in text if x.startswith("- The study's rule on the lattices"))
    step = max(worst(lattice4[t].to_numpy(), lattice[t].to_numpy()) for t in ("mfr", "pd"))
    assert f"largest change at N = 256: {100 * step:.1f} %; **not within 256 cases**." in rule


def test_the_workflows_convergence_summary_adds_to_the_rule_from_the_cases(tmp_path):
    """With results/convergence/summary.json published, the lines computed from the cases stay (they
    carry the changes by N) and the workflow's ratio and case-by-case verdict are added."""
    rng = np.random.default_rng(5)
    pd.DataFrame({"index": np.arange(64), "sweep": "lds", "status": "ok", "flagged": False, "case_id": range(64),
                  "regime": "normal", "h_um": 60.0, "d_um": 30.0, "v_mm_s": 10.0,
                  "mfr": rng.normal(0.45, 0.05, 64), "pd": rng.normal(0.40, 0.06, 64)}).to_csv(
        tmp_path / "cases_lds.csv", index=False)
    (tmp_path / "config.yaml").write_text(json.dumps({"sweeps": {"lds": {"partitions": [32, 64]}}}))
    (tmp_path / "convergence").mkdir()
    (tmp_path / "convergence" / "summary.json").write_text(json.dumps({
        "tolerance": 0.005, "sweeps": {"lds": {"converged_n": None, "cases_run": 64, "status": "not converged"}},
        "ratio_lattice_to_lds": {"value": None, "kind": "undefined", "text": "lds: not converged; no ratio"},
        "lds_case_by_case": {"first_holds": 40, "stable_from": None, "n_last": 64}}))
    text = summary(tmp_path, RANGES)
    assert "on the LDS: largest change at N = 64: " in text and "**not within 64 cases**." in text
    assert "- The workflow's convergence summary: lds: not converged; no ratio" in text
    assert "- The study's rule (five statistics within 0.5 %), lds: not converged (64 cases run)." in text
    assert ("- The study's rule case by case on the LDS (each case against the one before): does not hold for good "
            "within 64 cases (first holds at N = 40).") in text


def test_a_second_heldout_check_is_reported_beside_the_first(tmp_path):
    """heldout/ and heldout2/ each scored by spreadlab.heldout_points.score on known truth: the
    summary states both, the second under its own heading, with counts computed here with numpy;
    a second check chosen but not yet scored says so."""
    from spreadlab.heldout_points import score

    rng = np.random.default_rng(11)

    def scored(folder, shift):
        names = [f"p{i:02d}" for i in range(12)]
        truth = rng.uniform(0.3, 0.5, 12)
        predictions = pd.DataFrame({"name": names, "mfr": truth + shift, "mfr_model_sd": 0.004, "mfr_run_sd": 0.01})
        runs = pd.DataFrame({"name": np.repeat(names, 4), "mfr": np.repeat(truth, 4) + rng.normal(0, 0.01, 48)})
        table, summary = score(predictions, runs, "mfr")
        folder.mkdir()
        table.assign(target="mfr").rename(columns={"mfr": "predicted"}).to_csv(folder / "score.csv", index=False)
        (folder / "score.json").write_text(json.dumps([summary]))
        means = runs.groupby("name")["mfr"].mean().to_numpy()
        sd = np.sqrt(0.004 ** 2 + (0.01 ** 2 - 0.004 ** 2) / 4)
        return int(np.sum(np.abs(means - predictions["mfr"].to_numpy()) <= 1.959964 * sd))

    inside_first = scored(tmp_path / "heldout", 0.0)
    (tmp_path / "heldout2").mkdir()
    text = summary(tmp_path, RANGES)
    assert f"- mfr: {inside_first} of 12 points' seed means inside" in text
    second = text.split("- The second check, of the shipped surrogate")[1]
    assert second.splitlines()[1] == "  - " + NOT_YET
    (tmp_path / "heldout2").rmdir()
    inside_second = scored(tmp_path / "heldout2", 0.02)  # predictions 2 SDs of one run off: most points outside
    assert inside_second < 6
    second = summary(tmp_path, RANGES).split("- The second check, of the shipped surrogate")[1]
    assert f"  - mfr: {inside_second} of 12 points' seed means inside" in second
    assert second.count("  - outside: ") == 12 - inside_second
    # predictions 2 SDs off: the z^2 test says the stated SDs are too small, in words
    assert "the stated SDs are too small (intervals too narrow; p < 0.05)" in second.splitlines()[1]
