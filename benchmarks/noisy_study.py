#!/usr/bin/env python
"""The sampling-design study with noise (spreadlab.experiments.noisy_study): per design and noise
model, the cases needed before the map is right (its RMSE against a known truth at a target). No DEM.

Writes to --out: noisy_study_runs.csv (every run and checkpoint; noisy_study_runs.partial.csv while
it runs), noisy_study_summary.csv (cases needed per design, noise and target over the seeds),
noisy_study_rmse.csv (the map RMSE over the seeds at each n), the figure noisy_study.{png,pdf,csv}
and noisy_study_run.json (the command, wall and CPU seconds).

    PYTHONPATH=$PWD nice -n 10 .venv/bin/python benchmarks/noisy_study.py --out docs/sampling --seeds 8 --n-max 128
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import pandas as pd

from spreadlab.experiments.noisy_study import NOISE_MODELS, cases_needed, rmse_summary, run, summarise
from spreadmap.files import write_text_atomically


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="output directory (table CSVs, figure, run.json)")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--n-candidates", type=int, default=2048)
    ap.add_argument("--n-max", type=int, default=128)
    ap.add_argument("--targets", type=float, nargs="+", default=[0.01, 0.007, 0.005])
    ap.add_argument("--methods", nargs="+", default=["lds", "random", "lattice", "active"])
    ap.add_argument("--noises", nargs="+", default=list(NOISE_MODELS))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0, c0 = time.time(), time.process_time()
    table = run(args.methods, args.noises, range(args.seeds), n_max=args.n_max, n_candidates=args.n_candidates,
                log=lambda s: print(s, flush=True), partial=out / "noisy_study_runs.partial.csv")
    write_text_atomically(out / "noisy_study_runs.csv", table.to_csv(index=False))
    needed = pd.concat([cases_needed(table, t) for t in args.targets], ignore_index=True)
    summ = summarise(needed)
    write_text_atomically(out / "noisy_study_summary.csv", summ.to_csv(index=False))
    rs = rmse_summary(table)
    write_text_atomically(out / "noisy_study_rmse.csv", rs.to_csv(index=False))
    from spreadlab.experiments.experiment_plots import plot_noisy_study
    plot_noisy_study(table, summ, rs, out / "noisy_study")
    meta = {"command": "benchmarks/noisy_study.py " + " ".join(argv if argv is not None else sys.argv[1:]),
            "wall_s": time.time() - t0, "cpu_s": time.process_time() - c0,
            "seeds": args.seeds, "n_max": args.n_max, "targets": args.targets}
    write_text_atomically(out / "noisy_study_run.json", json.dumps(meta, indent=1))
    print(summ.to_string())
    print(json.dumps(meta))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
