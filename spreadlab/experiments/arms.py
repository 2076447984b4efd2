"""A study in arms: the same design points run under a few variants of the scene (arms), each case
rendered, run by YADE in its own process (its CPU time its own) and measured, every finished case
appended at once to a CSV (a run cut short keeps what it finished; a re-run skips what is there),
and a summary per point and arm against a reference arm.

Used by benchmarks/adhesion_scaling.py (density scaling under adhesion) and benchmarks/psd_cost.py
(the size distribution's cost and tails).
"""
from __future__ import annotations

import argparse
import csv
import io
import json
import math
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from spreadmap.case.identity import case_scene
from spreadmap.case.launcher import run_case
from spreadmap.case.render import render
from spreadmap.design import NAMES, TARGETS
from spreadmap.files import write_csv_atomically, write_text_atomically
from spreadmap.metrics.case import case_metrics
from spreadmap.table import usable as table_usable


def add_arguments(ap: argparse.ArgumentParser, points, arms, default_arms, keep: str) -> None:
    """The flags every arms study takes: --seeds, --arms, --points, --csv, --summary, --keep,
    --workers, --summary-only."""
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--arms", nargs="+", default=list(default_arms), choices=list(arms))
    ap.add_argument("--points", nargs="+", default=list(points), choices=list(points))
    ap.add_argument("--csv", required=True, help="the cases' table (appended case by case; a re-run skips its cases)")
    ap.add_argument("--summary", help="write the summary table (markdown) here")
    ap.add_argument("--keep", default=keep, help="the cases' folders")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--summary-only", action="store_true")


def pending(rows: list[dict], args, order_key) -> list[tuple[str, str, int]]:
    """(arm, point, seed) of the asked cases not in `rows`, sorted by `order_key`."""
    done = {(r["arm"], r["point"], int(r["seed"])) for r in rows}
    asked = sorted(((a, p, s) for a in args.arms for p in args.points for s in args.seeds), key=order_key)
    return [job for job in asked if job not in done]


def run_arm_case(cfg: dict, preset: str, point: dict, seed: int, keep: Path | str, columns,
                 adjust: Callable[[dict], dict] | None = None) -> tuple[dict, dict]:
    """Render, run and measure one case in its own folder under `keep`; `adjust` (optional) changes
    the scene's parameters before rendering (an arm that no config key spells; the case id stays the
    config's, so give such an arm its own `keep`).

    Returns
    -------
    tuple
        (row, params): the case's `columns` from its metrics (a case without a raw record: its
        outcome as status, flagged, the reason), its design point, CPU and wall time; and the
        parameters the scene received.
    """
    cid, params = case_scene(point, preset, cfg, seed)
    if adjust is not None:
        params = adjust(params)
    folder = Path(keep) / cid
    folder.mkdir(parents=True, exist_ok=True)
    script = folder / "case.py"
    write_text_atomically(script, render(params))
    result = run_case(script, folder / "raw.json", folder / "run.log", params["timeout_s"])
    row = {"case_id": cid, "seed": seed, **{k: point[k] for k in NAMES},
           "cpu_time": result["cpu_time"], "wall_time": result["wall_time"]}
    raw_path = folder / "raw.json"
    if raw_path.exists():
        out = case_metrics(json.loads(raw_path.read_text()), cfg["regime"], cfg["stability"], cfg["metrics"])
        row.update({k: out.get(k) for k in columns if k not in row and k in out})
    else:
        row.update({"status": result["outcome"], "flagged": True, "flag_reason": result["reason"]})
    return row, params


def read_rows(path: Path | str) -> list[dict]:
    """The rows of an arms CSV (strings), [] when it does not exist."""
    path = Path(path)
    if not path.exists():
        return []
    return list(csv.DictReader(io.StringIO(path.read_text())))


def number(x) -> float:
    """A CSV cell as a float (NaN for an empty or non-numeric one)."""
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def run_jobs(jobs: list[dict], run_one: Callable[[dict], dict], rows: list[dict], out: Path | str, columns,
             describe: Callable[[dict], str], workers: int = 2) -> list[dict]:
    """Run `jobs` (each `run_one(job)` gives a row) `workers` at a time, appending each finished row to
    `rows` and writing them all to `out` at once; prints `describe(row)` per case."""
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(run_one, job): job for job in jobs}
        for fut in as_completed(futures):
            row = fut.result()
            rows.append(row)
            write_csv_atomically(out, rows, columns)
            print(describe(row), flush=True)
    return rows


def run_study(args, order_key, job_of: Callable[[str, str, int], dict], run_one: Callable[[dict], dict], columns,
              summarise: Callable[[list[dict]], str], extra: Callable[[dict], str] = lambda row: "") -> list[dict]:
    """An arms study's main loop: the asked cases not yet in ``args.csv`` (``pending``, sorted by
    `order_key`) run two at a time (``run_jobs``; each row printed with its arm, point, seed, status,
    MFR, PD, `extra(row)`, CPU and flag), then the summary (`summarise` of every row) printed and
    written to ``args.summary`` when given. Returns the table's rows."""
    out = Path(args.csv)
    rows = read_rows(out)
    if not args.summary_only:
        jobs = [job_of(a, p, s) for a, p, s in pending(rows, args, order_key)]
        print(f"{len(jobs)} cases to run ({len(rows)} already in {out})", flush=True)
        run_jobs(jobs, run_one, rows, out, columns, workers=args.workers, describe=lambda row: (
            f"{row['arm']:10s} {row['point']:7s} s{row['seed']} {row.get('status')} mfr {number(row.get('mfr')):.4f} "
            f"pd {number(row.get('pd')):.4f} {extra(row)} cpu {row['cpu_time']:.0f} s {row.get('flag_reason') or ''}"))
    rows = read_rows(out)
    text = summarise(rows)
    print(text)
    if args.summary:
        write_text_atomically(Path(args.summary), text)
    return rows


def mean_se(group: list[dict], key: str) -> tuple[float, float, int]:
    """Mean of a column over rows, its SE from their spread (NaN with one row), and the count."""
    x = np.array([number(r.get(key)) for r in group])
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return math.nan, math.nan, 0
    return float(x.mean()), (float(x.std(ddof=1) / math.sqrt(len(x))) if len(x) > 1 else math.nan), len(x)


def usable(rows: list[dict]) -> list[dict]:
    """Rows of cases that finished and were not flagged: the product's one rule
    (spreadmap.table.usable) on the rows; a row read from the CSV holds its flag as text, so a case
    is flagged unless its flag reads False."""
    frame = pd.DataFrame({"status": [r.get("status") for r in rows],
                          "flagged": [str(r.get("flagged")) != "False" for r in rows]})
    return [r for r, keep in zip(rows, table_usable(frame)) if keep]


def arm_summary(rows: list[dict], points, arms, reference: str, keys=(*TARGETS, "coverage"),
                differences=TARGETS, extra: dict[str, Callable[[list[dict]], str]] | None = None) -> str:
    """A markdown table per point and arm: each of `keys` (mean of the seeds ± SE from their spread),
    the difference of each of `differences` from the `reference` arm ± SE, the CPU per case (median),
    and `extra` columns (header -> function of the arm's rows at the point, flagged included)."""
    extra = extra or {}
    header = (["point", "arm", *extra, "seeds", *keys, *[f"{k} - {reference}" for k in differences], "CPU s (median)"])
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    good = usable(rows)
    for point in points:
        ref = [r for r in good if r["point"] == point and r["arm"] == reference]
        for arm in arms:
            ran = [r for r in rows if r["point"] == point and r["arm"] == arm]
            if not ran:
                continue
            group = [r for r in good if r["point"] == point and r["arm"] == arm]
            cells = []
            for key in keys:
                m, se, _ = mean_se(group, key)
                cells.append(f"{m:.4f} ± {se:.4f}" if math.isfinite(se) else f"{m:.4f}")
            for key in differences:
                m, se, n = mean_se(group, key)
                mr, ser, nr = mean_se(ref, key)
                if n and nr and arm != reference:
                    s = math.sqrt((se if math.isfinite(se) else 0) ** 2 + (ser if math.isfinite(ser) else 0) ** 2)
                    cells.append(f"{m - mr:+.4f} ± {s:.4f}")
                else:
                    cells.append("")
            flagged = len(ran) - len(group)
            seeds = f"{len(group)}" + (f" (+{flagged} flagged/failed)" if flagged else "")
            cpu = np.nanmedian([number(r["cpu_time"]) for r in ran])
            lines.append("| " + " | ".join([point, arm, *[fn(ran) for fn in extra.values()], seeds, *cells, f"{cpu:.0f}"]) + " |")
    return "\n".join(lines) + "\n"
