"""The arms study's table (spreadlab.experiments.arms) on hand-made rows: means, SEs from the
seeds' spread, differences from the reference arm, and the rows it leaves out."""
import math

from spreadlab.experiments.arms import arm_summary, mean_se, read_rows, usable
from spreadmap.files import write_csv_atomically


def row(arm, point, seed, mfr, cpu, status="ok", flagged="False"):
    return {"arm": arm, "point": point, "seed": str(seed), "mfr": str(mfr), "cpu_time": str(cpu),
            "status": status, "flagged": flagged}


ROWS = [row("a", "p", 1, 0.30, 10), row("a", "p", 2, 0.34, 30),
        row("ref", "p", 1, 0.40, 100), row("ref", "p", 2, 0.40, 120),
        row("a", "p", 3, 0.90, 20, flagged="True"), row("ref", "p", 3, "", 500, status="failed", flagged="True")]


def test_mean_and_se_from_the_seeds():
    m, se, n = mean_se(usable(ROWS), "mfr")
    assert n == 4 and math.isclose(m, 0.36)
    m, se, n = mean_se([r for r in usable(ROWS) if r["arm"] == "a"], "mfr")
    # mean 0.32, SD of (0.30, 0.34) = 0.02 sqrt(2), SE = SD / sqrt(2) = 0.02
    assert math.isclose(m, 0.32) and math.isclose(se, 0.02) and n == 2


def test_summary_rows_differences_and_flagged_counts():
    text = arm_summary(ROWS, ["p"], ["a", "ref"], "ref", keys=("mfr",), differences=("mfr",),
                       extra={"n": lambda ran: str(len(ran))})
    lines = text.strip().splitlines()
    assert lines[0] == "| point | arm | n | seeds | mfr | mfr - ref | CPU s (median) |"
    # arm a: 0.32 ± 0.02; against ref (0.40 ± 0): -0.08 ± 0.02; CPU median of 10, 30, 20 (flagged counted)
    assert lines[2] == "| p | a | 3 | 2 (+1 flagged/failed) | 0.3200 ± 0.0200 | -0.0800 ± 0.0200 | 20 |"
    assert lines[3] == "| p | ref | 3 | 2 (+1 flagged/failed) | 0.4000 ± 0.0000 |  | 120 |"


def test_rows_round_trip_through_the_csv(tmp_path):
    path = tmp_path / "arms.csv"
    write_csv_atomically(path, ROWS, ["arm", "point", "seed", "mfr", "cpu_time", "status", "flagged"])
    assert read_rows(path) == ROWS
    assert read_rows(tmp_path / "missing.csv") == []
