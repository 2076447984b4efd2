#!/usr/bin/env python
"""Where a run's wall time went (issue 50): every job of a Snakemake run in WORKDIR, from Snakemake's
own logs, on the cores it ran on, coloured by kind, with the core time of the DEM cases, of the
loop's steps and of the analyses, and the idle core time (spreadmap/loop/timeline.py):

    .venv/bin/python tools/timeline.py WORKDIR --cores 2 --out docs/main_job/run_X/timeline

Reads every .snakemake/log/*.snakemake.log of WORKDIR (a run resumed after an interruption is
several logs, drawn one after the other) or the logs given with --log.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd

from spreadmap.loop.timeline import core_time, parse_log, place_on_cores
from spreadmap.loop.timeline_plot import draw_timeline


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("workdir", type=Path)
    parser.add_argument("--cores", type=int, required=True, help="the cores the run had (--cores)")
    parser.add_argument("--out", type=Path, required=True, help="output stem: <out>.png, .pdf, .csv, .json")
    parser.add_argument("--log", type=Path, nargs="*", help="Snakemake logs (default: all of WORKDIR's)")
    parser.add_argument("--title", default="the main job's timeline")
    parser.add_argument("--floor", default=None, help="the floor and powder, named above the title")
    args = parser.parse_args(argv)
    logs = args.log or sorted((args.workdir / ".snakemake" / "log").glob("*.snakemake.log"))
    if not logs:
        parser.error(f"no Snakemake log in {args.workdir / '.snakemake' / 'log'}")
    jobs = pd.concat([parse_log(p.read_text()) for p in logs], ignore_index=True).sort_values("start", ignore_index=True)
    placed = place_on_cores(jobs)
    summary = core_time(placed, args.cores)
    draw_timeline(placed, summary, args.out, args.title, floor=args.floor)
    args.out.with_suffix(".json").write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
