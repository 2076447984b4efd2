#!/usr/bin/env python
"""The map per CPU-second (spreadlab.experiments.cost_study): active batches by variance reduction
against the same per predicted CPU-second and the LDS, on a known truth at equal CPU. No DEM.

Writes to --out: cost_study_runs.csv (every run and checkpoint; cost_study_runs.partial.csv while it
runs), cost_study_needed.csv (per seed, the CPU hours each design needed to reach each target),
cost_study_summary.csv (their median and range, and the paired ratio), the figure
cost_study.{png,pdf,csv} and cost_study_run.json (the command, wall and CPU seconds).

    PYTHONPATH=$PWD nice -n 5 .venv/bin/python benchmarks/cost_study.py --out docs/sampling --seeds 8 --n-max 256
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import pandas as pd

from spreadlab.experiments.cost_study import METHODS, cpu_needed, summarise
from spreadlab.experiments.noisy_study import run
from spreadmap.files import write_text_atomically


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--n-max", type=int, default=256)
    ap.add_argument("--n-candidates", type=int, default=2048)
    ap.add_argument("--targets", type=float, nargs="+", default=[0.01, 0.007, 0.005])
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0, c0 = time.time(), time.process_time()
    table = run(METHODS, ["counting"], range(args.seeds), n_max=args.n_max, n_candidates=args.n_candidates,
                log=lambda s: print(s, flush=True), partial=out / "cost_study_runs.partial.csv")
    write_text_atomically(out / "cost_study_runs.csv", table.to_csv(index=False))
    (out / "cost_study_runs.partial.csv").unlink(missing_ok=True)
    needed = pd.concat([cpu_needed(table, t) for t in args.targets], ignore_index=True)
    write_text_atomically(out / "cost_study_needed.csv", needed.to_csv(index=False))
    summary = summarise(needed)
    write_text_atomically(out / "cost_study_summary.csv", summary.to_csv(index=False))
    from spreadlab.experiments.experiment_plots import plot_cost_study
    plot_cost_study(table, args.targets, out / "cost_study")
    meta = {"command": "benchmarks/cost_study.py " + " ".join(argv if argv is not None else sys.argv[1:]),
            "wall_s": time.time() - t0, "cpu_s": time.process_time() - c0, "seeds": args.seeds,
            "n_max": args.n_max, "targets": args.targets}
    write_text_atomically(out / "cost_study_run.json", json.dumps(meta, indent=1))
    print(summary.to_string())
    print(json.dumps(meta))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
