#!/usr/bin/env python
"""Wall time of a set of cases on N cores in the workflow's order (the costliest first: longest
processing time) against random orders, from the cases' measured CPU times (list scheduling: each
case starts on the first free core). Prints minutes.

    .venv/bin/python benchmarks/schedule_order.py docs/main_job/cases.csv --cores 2
"""
from __future__ import annotations

import argparse
import heapq
import sys

import numpy as np
import pandas as pd


def makespan(durations, cores: int) -> float:
    free = [0.0] * cores
    for d in durations:
        heapq.heappush(free, heapq.heappop(free) + float(d))
    return max(free)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", help="a cases table with a cpu_time column (s)")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--orders", type=int, default=2000, help="random orders drawn")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    t = pd.read_csv(args.cases)["cpu_time"].dropna().to_numpy()
    rng = np.random.default_rng(args.seed)
    random = np.array([makespan(rng.permutation(t), args.cores) for _ in range(args.orders)])
    bound = max(t.sum() / args.cores, t.max())
    print(f"{len(t)} cases, {t.sum() / 60:.1f} CPU min, longest {t.max() / 60:.1f} min, {args.cores} cores")
    print(f"costliest first: {makespan(sorted(t, reverse=True), args.cores) / 60:.1f} min (lower bound {bound / 60:.1f})")
    print(f"random order: mean {random.mean() / 60:.1f} min, 90th percentile {np.quantile(random, 0.9) / 60:.1f}, "
          f"worst {random.max() / 60:.1f} ({args.orders} orders)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
