#!/usr/bin/env python3
"""A floor's sweep read for drained piles per h/d band (issue 36): rolled-off spheres, the heap left
ahead of the blade, and the flags, split into piles that ran down and flows unsteady with the heap full.

    .venv/bin/python tools/floor_sweep.py CASES_CSV [--config config.yaml] [--out piles_by_band.csv]

CASES_CSV is a cases table (results/tables/cases.csv of a run, or a published one such as
docs/floors/flat_main_job/cases.csv); the run-down bound is the config's stability.min_heap_h2.
Prints the table as Markdown and writes it as CSV (spreadlab.floors.piles_by_band).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from spreadlab.floors import piles_by_band
from spreadmap.config import load
from spreadmap.files import atomic_path

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases")
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--out", help="CSV of the table")
    args = ap.parse_args(argv)
    bound = load(args.config)["stability"]["min_heap_h2"]
    table = piles_by_band(pd.read_csv(args.cases), bound)
    print(f"run-down bound: {bound} h^2 ahead of the blade at the window's end")
    print(table.to_markdown(index=False, floatfmt=".3g"))
    if args.out:
        with atomic_path(args.out) as tmp:
            table.to_csv(tmp, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
