#!/usr/bin/env python
"""What one DEM case costs at each fidelity preset: wall and CPU time per case, particle-steps per
CPU second, and each preset's CPU time relative to a baseline preset, with the MFR and PD of each
case beside its cost.

The cases are the named design points of config.yaml ``fidelity.points`` (``--points`` picks some
by name) at every preset of ``--presets`` and every packing seed of ``--seeds``, all in one run.
Each case is rendered with spreadmap.case.render and run with spreadmap.case.launcher.run_case in a
directory of its own (a temporary one, removed afterwards, unless ``--keep DIR``), ``--workers``
YADE processes at once, each single-threaded as in the workflow (one worker process per running
case, so that the CPU time that run_case reads from the process's children is that case's alone).

The job order interleaves the presets: point by point and seed by seed, every preset's case of
that point is queued before the next point starts. Whatever else the machine does during the run
(another job starting or ending, thermal throttling) thus falls on all presets alike instead of
on whichever preset happened to run last. CPU time is the cost measure to compare: it is far less
disturbed than wall time by a busy machine. It includes YADE's start-up (about 1.5 CPU seconds on
the 2-core development machine), which weighs on the cheap smoke cases.

Prints the date, CPU model, core count and load average, then one table per preset and the cases
of that preset; ``--csv PATH`` also writes one row per case. Exits 1, after printing, if any case
did not end "ok" (failed, timed out, refused, or blown up).

    .venv/bin/python benchmarks/case_cost.py                                  # every point, smoke fast default
    .venv/bin/python benchmarks/case_cost.py --points normal --presets smoke --seeds 1 2 --csv cost.csv
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import multiprocessing
import os
import statistics
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from spreadmap.host import description_lines

ROOT = Path(__file__).resolve().parent.parent

CSV_COLUMNS = ["preset", "point", "seed", "case_id", "outcome", "status", "reason", "n_particles", "steps",
               "estimated_steps", "wall_time", "cpu_time", "particle_steps_per_cpu_s", "mfr", "pd", "regime",
               "workdir"]


def build_jobs(config: dict, points: list[str], presets: list[str], seeds: list[int], base: Path) -> list[dict]:
    """One job per (point, seed, preset), presets innermost: the interleaved order."""
    from spreadmap.case.identity import case_scene
    from spreadmap.case.render import template_sha256

    sha = template_sha256()
    jobs = []
    for name in points:
        point = config["fidelity"]["points"][name]
        for seed in seeds:
            for preset in presets:
                cid, params = case_scene(point, preset, config, seed, sha)
                jobs.append({"point": name, "preset": preset, "seed": seed, "params": params,
                             "workdir": str(base / cid)})
    return jobs


def run_job(job: dict) -> dict:
    """Render and run one case in its directory (in a worker process); returns the launcher result
    and the raw record ({} when YADE wrote none)."""
    from spreadmap.case.launcher import run_case
    from spreadmap.case.render import render
    from spreadmap.files import write_text_atomically

    workdir = Path(job["workdir"])
    workdir.mkdir(parents=True, exist_ok=True)
    raw_path = workdir / "raw.json"
    raw_path.unlink(missing_ok=True)  # a stale result of an earlier run in a kept directory
    script = workdir / "case.py"
    write_text_atomically(script, render(job["params"]))
    result = run_case(script, raw_path, workdir / "run.log", job["params"]["timeout_s"])
    raw = json.loads(raw_path.read_text()) if raw_path.exists() else {}
    return {"result": result, "raw": raw}


def case_row(job: dict, result: dict, raw: dict, config: dict) -> dict:
    from spreadmap.metrics import case_metrics

    params = job["params"]
    row = {"preset": job["preset"], "point": job["point"], "seed": job["seed"], "case_id": params["case_id"],
           "outcome": result["outcome"], "status": raw.get("status", "failed"), "reason": result.get("reason", ""),
           "n_particles": params["n_particles"], "steps": math.nan, "estimated_steps": params["estimated_steps"],
           "wall_time": result["wall_time"], "cpu_time": result["cpu_time"], "particle_steps_per_cpu_s": math.nan,
           "mfr": math.nan, "pd": math.nan, "regime": "", "workdir": job["workdir"]}
    if raw:
        metrics = case_metrics({**raw, "cpu_time": result["cpu_time"]}, config["regime"], config["stability"],
                               config["metrics"])
        row.update(n_particles=metrics["n_particles"], steps=metrics["steps"], mfr=metrics["mfr"],
                   pd=metrics["pd"], regime=metrics["regime"])
        if not row["reason"]:
            row["reason"] = metrics["flag_reason"]
        if result["cpu_time"] > 0 and finite(row["steps"]):
            row["particle_steps_per_cpu_s"] = row["n_particles"] * row["steps"] / result["cpu_time"]
    return row


def finite(x) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x)


def median(values) -> float:
    values = [v for v in values if finite(v)]
    return statistics.median(values) if values else math.nan


def maximum(values) -> float:
    values = [v for v in values if finite(v)]
    return max(values) if values else math.nan


def fmt(x, spec: str = ".2f") -> str:
    return format(x, spec) if finite(x) else "-"


def print_report(rows: list[dict], presets: list[str], baseline: str) -> None:
    by_preset = {p: [r for r in rows if r["preset"] == p] for p in presets}
    base_cpu = median(r["cpu_time"] for r in by_preset.get(baseline, []) if r["outcome"] == "ok")
    if not finite(base_cpu):
        print(f"\nbaseline preset {baseline!r} was not run (or no case of it ended ok): no CPU ratios")
    summary = []
    for preset in presets:
        cases = by_preset[preset]
        ok = [r for r in cases if r["outcome"] == "ok"]
        cpu_median = median(r["cpu_time"] for r in ok)
        ratio = cpu_median / base_cpu if finite(base_cpu) and base_cpu > 0 else math.nan
        summary.append((preset, len(cases), len(ok), cpu_median, ratio))
        print(f"\n=== preset {preset}: {len(cases)} cases, {len(ok)} ok ===")
        print(f"  wall time per case [s]   median {fmt(median(r['wall_time'] for r in ok), '8.2f')}"
              f"   max {fmt(maximum(r['wall_time'] for r in ok), '8.2f')}")
        print(f"  CPU time per case [s]    median {fmt(cpu_median, '8.2f')}"
              f"   max {fmt(maximum(r['cpu_time'] for r in ok), '8.2f')}")
        print(f"  particle-steps / CPU s   median {fmt(median(r['particle_steps_per_cpu_s'] for r in ok), '8.3g')}")
        print(f"  median CPU time / {baseline}'s   {fmt(ratio, '.3f')}")
        print(f"  {'point':<20} {'seed':>4} {'outcome':<8} {'particles':>9} {'steps':>8} {'wall s':>8} {'cpu s':>8}"
              f" {'psteps/cpu-s':>12} {'MFR':>7} {'PD':>7}  regime")
        for r in cases:
            print(f"  {r['point']:<20} {r['seed']:>4} {r['outcome']:<8} {r['n_particles']:>9} "
                  f"{fmt(r['steps'], '8.0f'):>8} {fmt(r['wall_time'], '8.2f')} {fmt(r['cpu_time'], '8.2f')} "
                  f"{fmt(r['particle_steps_per_cpu_s'], '12.3g'):>12} {fmt(r['mfr'], '7.4f'):>7} "
                  f"{fmt(r['pd'], '7.4f'):>7}  {r['regime']}"
                  + (f"  ({r['reason']})" if r["outcome"] != "ok" and r["reason"] else ""))
    print(f"\n=== summary (CPU ratio against {baseline}) ===")
    print(f"  {'preset':<12} {'cases':>5} {'ok':>4} {'median cpu s':>12} {'cpu ratio':>9}")
    for preset, n, n_ok, cpu, ratio in summary:
        print(f"  {preset:<12} {n:>5} {n_ok:>4} {fmt(cpu, '12.2f')} {fmt(ratio, '9.3f')}")


def write_csv(rows: list[dict], path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=CSV_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", default=str(ROOT / "config.yaml"), help="configuration file (default: %(default)s)")
    parser.add_argument("--points", nargs="+", metavar="NAME",
                        help="names of fidelity.points to run (default: all of them)")
    parser.add_argument("--presets", nargs="+", default=["smoke", "fast", "default"], metavar="PRESET",
                        help="presets to run (default: %(default)s)")
    parser.add_argument("--seeds", nargs="+", type=int, default=[1], metavar="SEED",
                        help="packing seeds (default: %(default)s)")
    parser.add_argument("--workers", type=int, default=2, help="YADE processes at once (default: %(default)s)")
    parser.add_argument("--baseline", default="default",
                        help="preset whose median CPU time the others are divided by (default: %(default)s)")
    parser.add_argument("--keep", metavar="DIR", help="keep every case's directory under DIR (default: a temporary "
                        "directory, removed at the end)")
    parser.add_argument("--csv", metavar="PATH", help="write one row per case to this CSV file")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    from spreadmap import config as spreadmap_config

    config = spreadmap_config.load(args.config)
    known_points = list((config.get("fidelity") or {}).get("points") or {})
    points = args.points or known_points
    unknown = [p for p in points if p not in known_points]
    if unknown or not points:
        sys.exit(f"case_cost.py: unknown point(s) {unknown}; fidelity.points of {args.config}: {known_points}")
    unknown = [p for p in args.presets if p not in config["presets"]]
    if unknown:
        sys.exit(f"case_cost.py: unknown preset(s) {unknown}; presets of {args.config}: {sorted(config['presets'])}")
    if args.workers < 1:
        sys.exit("case_cost.py: --workers must be at least 1")
    presets = list(dict.fromkeys(args.presets))
    seeds = list(dict.fromkeys(args.seeds))

    print("\n".join(description_lines()))
    print(f"python: {sys.executable}")
    if args.keep:
        base = Path(args.keep).resolve()
        base.mkdir(parents=True, exist_ok=True)
        tmp = None
    else:
        tmp = tempfile.TemporaryDirectory(prefix="spreadmap-case-cost-")
        base = Path(tmp.name)
    jobs = build_jobs(config, points, presets, seeds, base)
    print(f"{len(jobs)} cases: points {points} x seeds {seeds} x presets {presets} (presets interleaved), "
          f"{args.workers} single-threaded YADE processes at once, in {base}"
          + ("" if args.keep else " (removed at the end)"))
    sys.stdout.flush()

    rows: list[dict | None] = [None] * len(jobs)
    start = time.perf_counter()
    # one worker process per running case: run_case's CPU time (RUSAGE_CHILDREN) is then that case's
    context = multiprocessing.get_context("spawn")
    try:
        with ProcessPoolExecutor(max_workers=args.workers, mp_context=context) as pool:
            futures = {pool.submit(run_job, job): i for i, job in enumerate(jobs)}
            for done, future in enumerate(as_completed(futures), 1):
                i = futures[future]
                job = jobs[i]
                try:
                    out = future.result()
                    rows[i] = case_row(job, out["result"], out["raw"], config)
                except Exception as error:  # the launcher itself failed (no yade, disk full, ...)
                    rows[i] = case_row(job, {"outcome": "failed", "reason": f"{type(error).__name__}: {error}",
                                             "wall_time": math.nan, "cpu_time": math.nan}, {}, config)
                r = rows[i]
                print(f"[{done}/{len(jobs)}] {r['case_id']}: {r['outcome']}, wall {fmt(r['wall_time'])} s, "
                      f"cpu {fmt(r['cpu_time'])} s", flush=True)
    finally:
        if tmp is not None:
            tmp.cleanup()
            for r in rows:
                if r is not None:
                    r["workdir"] = ""  # removed
    elapsed = time.perf_counter() - start
    print(f"\nall {len(jobs)} cases in {elapsed:.1f} s wall time; "
          f"load average at the end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print_report(rows, presets, args.baseline)
    if args.csv:
        write_csv(rows, Path(args.csv))
        print(f"\nper-case rows written to {args.csv}")
    bad = [r for r in rows if r["outcome"] != "ok"]
    if bad:
        print(f"\n{len(bad)} case(s) did not end ok: " + ", ".join(f"{r['case_id']} ({r['outcome']})" for r in bad))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
