"""Reading Snakemake's dry-run output (`snakemake -n`): the jobs it plans, per rule (for the
workflow's tests and benchmarks/main_job.py)."""
from __future__ import annotations


def planned_jobs(output: str) -> dict[str, int]:
    """Job counts per rule from the last 'Job stats' table of a dry run."""
    counts, inside = {}, False
    for line in output.splitlines():
        if line.startswith("Job stats"):
            inside, counts = True, {}
            continue
        parts = line.split()
        if inside and len(parts) == 2 and parts[1].isdigit():
            counts[parts[0]] = int(parts[1])
        elif inside and parts[:1] == ["total"]:
            inside = False
    return counts
