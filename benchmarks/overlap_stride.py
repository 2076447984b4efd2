#!/usr/bin/env python
"""What reading the peak overlap every step costs: the same case with record_overlap every step
(`every_step`, the scene before issue 50) and at the scene's stride (`stride`: a quarter of the
shortest contact, 2 steps at `default`; the stability check divides by
spreadmap.metrics.case.overlap_sampling_factor), in one run.

The record does not act on the spheres, so the two arms' MFR and PD must be equal to the bit; the
CPU ratio stride / every_step is the lever. Both arms of a (point, seed) run at the same time, one
per core, so a busy machine slows both alike.

    .venv/bin/python benchmarks/overlap_stride.py --csv docs/case_cost/overlap_stride.csv --seeds 1 2
"""
from __future__ import annotations

import argparse
import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from spreadlab.experiments.arms import number, read_rows, run_arm_case
from spreadmap import config as spreadmap_config
from spreadmap.files import write_csv_atomically, write_text_atomically
from spreadmap.metrics.case import overlap_sampling_factor

ROOT = Path(__file__).resolve().parent.parent
POINTS = {"thin": (0.30, 40.0, 60.0, 10.0), "mid": (0.30, 30.0, 65.0, 10.0), "wide": (0.30, 20.0, 70.0, 10.0)}
ARMS = ("every_step", "stride")
COLUMNS = ("arm", "point", "seed", "case_id", "overlap_every", "sampling_factor", "status", "flagged", "mfr", "pd",
           "peak_overlap_free", "steps", "n_particles", "cpu_time", "wall_time")


def every_step(params: dict) -> dict:
    return {**params, "overlap_every": 1}


def run_one(job: dict) -> dict:
    f, d, h, v = POINTS[job["point"]]
    point = {"f": f, "d_um": d, "h_um": h, "v_mm_s": v}
    row, params = run_arm_case(job["config"], "default", point, job["seed"], Path(job["keep"]) / job["arm"], COLUMNS,
                               adjust=every_step if job["arm"] == "every_step" else None)
    row.update({"arm": job["arm"], "point": job["point"], "overlap_every": params["overlap_every"],
                "sampling_factor": overlap_sampling_factor(params)})
    return row


def summary(rows: list[dict]) -> str:
    lines = ["| point | seed | stride (steps) | factor | MFR equal | PD equal | CPU every step (s) | CPU stride (s) | ratio |",
             "|---|---|---|---|---|---|---|---|---|"]
    ratios = []
    for point in POINTS:
        for seed in sorted({int(r["seed"]) for r in rows}):
            pair = {r["arm"]: r for r in rows if r["point"] == point and int(r["seed"]) == seed}
            if set(pair) != set(ARMS):
                continue
            a, b = pair["every_step"], pair["stride"]
            ratio = number(b["cpu_time"]) / number(a["cpu_time"])
            ratios.append(ratio)
            lines.append(f"| {point} | {seed} | {b['overlap_every']} | {number(b['sampling_factor']):.3f} | "
                         f"{a['mfr'] == b['mfr']} | {a['pd'] == b['pd']} | {number(a['cpu_time']):.1f} | "
                         f"{number(b['cpu_time']):.1f} | {ratio:.3f} |")
    if ratios:
        logs = np.log(ratios)
        se = logs.std(ddof=1) / math.sqrt(len(logs)) if len(logs) > 1 else math.nan
        lines.append(f"\nCPU stride / every step: geometric mean {math.exp(logs.mean()):.3f} "
                     f"(95 % CI {math.exp(logs.mean() - 1.96 * se):.3f}-{math.exp(logs.mean() + 1.96 * se):.3f}), "
                     f"{len(ratios)} pairs")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--points", nargs="+", default=list(POINTS), choices=list(POINTS))
    ap.add_argument("--csv", required=True)
    ap.add_argument("--summary")
    ap.add_argument("--keep", default="/tmp/overlap_stride")
    args = ap.parse_args()
    cfg = spreadmap_config.load(args.config)
    rows = read_rows(args.csv)
    done = {(r["arm"], r["point"], int(r["seed"])) for r in rows}
    with ProcessPoolExecutor(max_workers=2) as pool:
        for seed in args.seeds:
            for point in args.points:
                jobs = [{"arm": arm, "point": point, "seed": seed, "config": cfg, "keep": args.keep}
                        for arm in ARMS if (arm, point, seed) not in done]
                for row in pool.map(run_one, jobs):  # the pair side by side, one per core
                    rows.append(row)
                    write_csv_atomically(args.csv, rows, COLUMNS)
                    print(f"{row['arm']:10s} {point:5s} s{seed} mfr {number(row.get('mfr')):.6f} "
                          f"cpu {number(row['cpu_time']):.1f} s", flush=True)
    text = summary(rows)
    print(text)
    if args.summary:
        write_text_atomically(Path(args.summary), text)


if __name__ == "__main__":
    main()
