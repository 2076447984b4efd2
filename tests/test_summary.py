"""The run summary's counts and its readable text."""
import pandas as pd

from spreadmap.summary import run_summary, summary_text


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


def test_sets_without_cases():
    empty = pd.DataFrame(columns=["case_id", "status", "flagged", "regime", "flag_reason"])
    summary = run_summary({"points": empty})
    assert summary["unique_cases"] == 0 and summary["sets"]["points"]["cases"] == 0
    assert summary["all"]["cases"] == 0 and "points" in summary_text(summary)
