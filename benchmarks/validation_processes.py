#!/usr/bin/env python
"""Wall time of the surrogate's validation (rule surrogate_validation) in one process and in two, on a
published run's table, the same tables checked equal (issue 50: the main job's tail).

    .venv/bin/python benchmarks/validation_processes.py [--table docs/main_job/run_2026-12-06/cases.csv] [--repeats 1]

--repeats sets surrogate.cv_repeats (the shipped 3 takes ~10 min in one process); the ratio is what
carries over.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import pandas as pd

from spreadmap import config as spreadmap_config
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import read_table
from spreadmap.surrogate import validate_surrogate

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--table", default=str(ROOT / "docs" / "main_job" / "run_2026-12-06" / "cases.csv"))
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--repeats", type=int, default=1)
    args = ap.parse_args()
    cfg = spreadmap_config.load(args.config)
    table = case_noise(read_table(args.table), cfg.get("noise_model"), cfg["noise_calibration"],
                       cfg["metrics"]["counting_noise_c"])
    settings = {**cfg["surrogate"], "cv_repeats": args.repeats}
    seconds, results = {}, {}
    for n_jobs in (1, 2):
        start = time.perf_counter()
        results[n_jobs] = validate_surrogate(table, settings, log=lambda *a: None, n_jobs=n_jobs)
        seconds[n_jobs] = time.perf_counter() - start
        print(f"n_jobs {n_jobs}: {seconds[n_jobs]:.1f} s", flush=True)
    pd.testing.assert_frame_equal(results[1].validation, results[2].validation, check_exact=True)
    print(f"{args.table}: {len(table)} rows, cv_repeats {args.repeats}: one process {seconds[1]:.1f} s, two "
          f"{seconds[2]:.1f} s, ratio {seconds[2] / seconds[1]:.3f}; validation tables equal to the bit")


if __name__ == "__main__":
    main()
