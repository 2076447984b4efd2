"""The run summary's counts and its readable text."""
import pandas as pd

from spreadmap.run_report import run_summary, summary_text


def test_counts_and_reasons_said_once():
    table = pd.DataFrame({
        "case_id": ["a", "b", "c"], "status": ["ok", "ok", "failed"], "regime": ["normal", "jamming", ""],
        "flagged": [False, True, True], "wall_time": [10.0, 20.0, float("nan")],
        "flag_reason": ["", "peak overlap 0.0517 R > 0.05 R", "failed: timed out after 2 s wall time"],
    })
    summary = run_summary({"lds": table})
    s = summary["sets"]["lds"]
    assert (s["cases"], s["done"], s["failed"], s["flagged"], s["usable"]) == (3, 2, 1, 2, 1)
    assert s["regimes"] == {"normal": 1, "jamming": 1} and s["wall_time_s"]["median"] == 15.0
    text = summary_text(summary)
    assert "    c: failed: timed out after 2 s wall time\n" in text  # the status is not said twice
    assert "    b: ok: peak overlap 0.0517 R > 0.05 R\n" in text
    assert "a:" not in text


def test_the_summary_names_its_floor():
    from spreadmap.case.substrate import floor_label

    table = pd.DataFrame({"case_id": ["a"], "status": ["ok"], "regime": ["normal"], "flagged": [False], "flag_reason": [""]})
    floor = floor_label({"scene": {"substrate": {"kind": "rough", "jitter": 0.5}}})
    summary = run_summary({"lds": table}, floor=floor)
    assert summary["floor"] == floor
    assert summary_text(summary).splitlines()[1] == f"  floor: {floor}"
    assert "floor" not in run_summary({"lds": table})  # not known: not said


def test_sets_without_cases():
    empty = pd.DataFrame(columns=["case_id", "status", "flagged", "regime", "flag_reason"])
    summary = run_summary({"points": empty})
    assert summary["unique_cases"] == 0 and summary["sets"]["points"]["cases"] == 0
    assert summary["all"]["cases"] == 0 and "points" in summary_text(summary)


def test_regime_rule_stated_and_stale_labels_counted():
    """With the config's rule, the summary says it and counts labels the rule would not give."""
    rules = {"jam_mfr_max": 0.05, "short_feed_coverage_min": 0.5, "short_feed_thickness_min": 0.25}
    table = pd.DataFrame({
        "case_id": ["a", "b", "c", "d"], "status": ["ok", "ok", "ok", "failed"],
        "regime": ["normal", "short_feed", "normal", ""], "flagged": [False, False, False, True],
        "flag_reason": ["", "", "", "failed: x"], "mfr": [0.3, 0.3, 0.01, float("nan")],
        "coverage": [0.9, 0.3, 0.9, float("nan")], "thickness_ratio": [0.5, 0.5, 0.5, float("nan")],
    })
    summary = run_summary({"lds": table}, rules)
    assert summary["sets"]["lds"]["stale_regime_labels"] == 1  # c: MFR 0.01 is jamming by the rule
    assert summary["sets"]["lds"]["regimes"] == {"normal": 2, "short_feed": 1}
    text = summary_text(summary)
    assert "regime rule: jamming if MFR < 0.05; else short feed if coverage < 0.5" in text
    assert "1 finished cases carry a regime label that the rule does not give" in text
    old = table.drop(columns=["coverage", "thickness_ratio"])  # metrics from before the layer columns
    assert run_summary({"lds": old}, rules)["sets"]["lds"]["stale_regime_labels"] == 3
