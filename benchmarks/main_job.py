#!/usr/bin/env python
"""What the main job costs end to end: the wall time of `snakemake --cores 2` on a fresh copy of
the workflow, the number of run_case jobs, and the per-case wall and CPU times from its tables.

The workflow (Snakefile, config.yaml, rules, scripts, yade_scripts, schemas, profiles, envs) is
copied into a fresh directory (``--workdir``, default a new temporary directory, kept after a real
run so that its results can be looked at), so that nothing is re-used and the repository's own
results/ is never touched. ``--config KEY=VALUE ...`` is passed through to snakemake (e.g.
``--config preset=fast``). The venv's snakemake (next to this Python) runs the job with the
workflow's default profile; its whole output goes to main_job.log in the work directory.

Printed: the date, CPU and core count; the planned jobs per rule (from a dry run); the end-to-end
wall time; the run_case jobs started and finished; over the distinct cases of the converge run's
table and results/tables/*.csv, their count and the median and max of wall_time and cpu_time per
case; and the converge run's summary (where it stopped, why, the path).
Exits with snakemake's exit status.

``--dry-run`` only plans (snakemake -n) and prints the number of jobs per rule.

    .venv/bin/python benchmarks/main_job.py --dry-run
    .venv/bin/python benchmarks/main_job.py --workdir /tmp/mainjob --config preset=fast
"""
from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from spreadlab.dryrun import planned_jobs
from spreadmap.host import description_lines

ROOT = Path(__file__).resolve().parent.parent
WORKFLOW_FILES = ["Snakefile", "config.yaml", "rules", "scripts", "yade_scripts", "schemas", "profiles", "envs"]
SNAKEMAKE = Path(sys.executable).parent / "snakemake"

PROGRESS = re.compile(r"^\d+ of \d+ steps \(.*\) done")


def copy_workflow(workdir: Path) -> None:
    workdir.mkdir(parents=True, exist_ok=True)
    for name in WORKFLOW_FILES:
        src = ROOT / name
        if src.is_dir():
            shutil.copytree(src, workdir / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        elif src.exists():
            shutil.copy2(src, workdir / name)


def snakemake_command(args, *extra: str) -> list[str]:
    cmd = [str(SNAKEMAKE), "--cores", str(args.cores), *extra]
    if args.config:
        cmd += ["--config", *args.config]
    return cmd


def dry_run(args, workdir: Path) -> tuple[int, dict[str, int], str]:
    run = subprocess.run(snakemake_command(args, "-n"), cwd=workdir, capture_output=True, text=True)
    output = run.stdout + run.stderr
    return run.returncode, planned_jobs(output), output


def print_plan(counts: dict[str, int]) -> None:
    print("planned jobs per rule:")
    for rule, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])):
        if rule != "total":
            print(f"  {rule:<28} {n:>6}")
    print(f"  {'total':<28} {counts.get('total', sum(counts.values())):>6}")
    print(f"run_case jobs planned: {counts.get('run_case', 0)}")


def table_summary(results: Path) -> list[str]:
    """Count, median and max of wall_time and cpu_time over the distinct cases of the tables (the
    converge run's and results/tables/*.csv), and where the converge run stopped and why."""
    import pandas as pd

    files = sorted((results / "tables").glob("*.csv")) + sorted((results / "converge").glob("table.csv"))
    if not files:
        return [f"no results tables in {results}"]
    frames = [pd.read_csv(f) for f in files]
    table = pd.concat([f for f in frames if "case_id" in f.columns], ignore_index=True)
    table = table.drop_duplicates("case_id")
    lines = [f"cases in {', '.join(str(f.relative_to(results)) for f in files)}: {len(table)} distinct"]
    if "status" in table.columns:
        lines.append("  by status: " + ", ".join(f"{s} {n}" for s, n in table["status"].value_counts().items()))
    for column in ("wall_time", "cpu_time"):
        values = pd.to_numeric(table[column], errors="coerce").dropna() if column in table.columns else pd.Series([])
        if len(values):
            lines.append(f"  {column:<10} per case [s]: median {values.median():9.2f}   max {values.max():9.2f}"
                         f"   (n = {len(values)})")
        else:
            lines.append(f"  {column:<10} per case [s]: n/a (no values in the tables)")
    if "cpu_time" in table.columns:
        lines.append(f"  CPU time of the cases: {pd.to_numeric(table['cpu_time'], errors='coerce').sum() / 3600:.2f} h")
    summary = results / "converge" / "summary.txt"
    if summary.exists():
        lines += ["converge run (results/converge/summary.txt):"] + ["  " + s for s in summary.read_text().splitlines()]
    return lines


def run_job(args, workdir: Path) -> tuple[int, float, dict]:
    """Run the job; its output goes to main_job.log, progress lines to stdout."""
    log_path = workdir / "main_job.log"
    counted = {"started": 0, "finished": 0, "errors": 0}
    start = time.perf_counter()
    with open(log_path, "w") as log:
        proc = subprocess.Popen(snakemake_command(args), cwd=workdir, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True, bufsize=1)
        try:
            for line in proc.stdout:
                log.write(line)
                stripped = line.strip()
                if stripped in ("rule run_case:", "localrule run_case:"):
                    counted["started"] += 1
                elif stripped.startswith("Finished jobid:") and "(Rule: run_case)" in stripped:
                    counted["finished"] += 1
                elif stripped.startswith("Error in rule run_case"):
                    counted["errors"] += 1
                if PROGRESS.match(stripped):
                    print(f"  [{time.perf_counter() - start:8.1f} s] {stripped}", flush=True)
            code = proc.wait()
        except KeyboardInterrupt:
            proc.terminate()  # snakemake stops its jobs on SIGTERM
            proc.wait()
            raise
    return code, time.perf_counter() - start, counted


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workdir", help="fresh (missing or empty) directory to copy the workflow into "
                        "(default: a new temporary directory)")
    parser.add_argument("--config", nargs="+", action="extend", metavar="KEY=VALUE",
                        help="config overrides passed through to snakemake --config")
    parser.add_argument("--cores", type=int, default=2, help="snakemake --cores (default: %(default)s)")
    parser.add_argument("--dry-run", "-n", action="store_true",
                        help="only plan (snakemake -n) and print the jobs per rule")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    if not SNAKEMAKE.exists():
        print(f"main_job.py: no snakemake next to {sys.executable} ({SNAKEMAKE}); run with the venv's python",
              file=sys.stderr)
        return 2
    if args.workdir:
        workdir = Path(args.workdir).resolve()
        if workdir.exists() and any(workdir.iterdir()):
            print(f"main_job.py: --workdir {workdir} is not empty; give a new or empty directory", file=sys.stderr)
            return 2
        temporary = False
    else:
        workdir = Path(tempfile.mkdtemp(prefix="spreadmap-main-job-"))
        temporary = True
    copy_workflow(workdir)
    print("\n".join(description_lines()))
    print(f"workflow copied to {workdir}")
    print(f"snakemake: {' '.join(snakemake_command(args))}")

    code, counts, output = dry_run(args, workdir)
    if code != 0:
        print(output[-3000:])
        print(f"main_job.py: the dry run failed (exit {code})", file=sys.stderr)
        return code
    print_plan(counts)
    if args.dry_run:
        if temporary:
            shutil.rmtree(workdir, ignore_errors=True)
        return 0

    print("running the main job (output in main_job.log of the work directory) ...", flush=True)
    code, elapsed, counted = run_job(args, workdir)
    print(f"\nsnakemake exit status: {code}")
    print(f"end-to-end wall time: {elapsed:.1f} s ({elapsed / 60:.1f} min)")
    print(f"run_case jobs: {counts.get('run_case', 0)} planned, {counted['started']} started "
          f"(retries included), {counted['finished']} finished, {counted['errors']} errors")
    for line in table_summary(workdir / "results"):
        print(line)
    print(f"results kept in {workdir / 'results'}")
    return code


if __name__ == "__main__":
    sys.exit(main())
