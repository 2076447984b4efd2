"""benchmarks/machine_speed.py picks the published run's median-cost and costliest usable cases
(the YADE run itself is the published case re-run: see tests/case/test_reproduce_published_yade.py)."""
from __future__ import annotations

import pandas as pd
from conftest import script_module

speed = script_module("benchmarks/machine_speed.py")


def table():
    return pd.DataFrame({"status": ["ok", "ok", "ok", "failed", "ok", "ok"],
                         "flagged": [False, False, True, False, False, "False"],
                         "cpu_time": [10.0, 30.0, 900.0, 5000.0, 20.0, 400.0]})


def test_median_and_costliest_usable_cases():
    chosen = speed.reference_cases(table(), quick=False)
    # usable CPUs 10, 30, 20, 400: median 25, nearest 30 (or 20: the first nearest), costliest 400 (the
    # flagged 900 and the failed 5000 are not usable)
    assert list(chosen["cpu_time"]) in ([20.0, 400.0], [30.0, 400.0])
    assert list(speed.reference_cases(table(), quick=True)["cpu_time"]) in ([20.0], [30.0])


def test_the_published_run_has_both():
    chosen = speed.reference_cases(pd.read_csv(speed.PUBLISHED), quick=False)
    assert len(chosen) == 2 and chosen["cpu_time"].iloc[1] > 5 * chosen["cpu_time"].iloc[0]
    assert chosen["d_um"].iloc[1] < 15  # the costly corner is the small spheres'
