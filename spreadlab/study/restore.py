"""Finished cases restored from a published cases table (docs/study/cases_*.csv) into a workflow
directory, so that a run on a new machine resumes where the published one stopped instead of
re-running hours of YADE.

A published row is what the workflow's results table held for the case: the case's metrics (what
rules/metrics.smk wrote to its metrics.json), its labels in that table (sweep, index, batch, ...)
and its benchmark (wall time, peak memory). A restored case gets back its metrics.json and
benchmark.tsv, plus restored.json saying where they came from; its raw YADE record is not
published and stays missing, so the workflow (rules/common.smk, `case_raw_input`) does not ask for
it. A row is restored under its own case id, which carries the content key of the scene it was run
with (spreadmap.case.identity): the workflow re-uses it only when its own configuration and template give
the same key, so a published case is never taken for a case of another material or scene. A table
whose ids have no content key (published before issue 35) does not say which scene its cases were
run with: it is refused, naming the table, before anything is restored. A case directory that
holds a raw record is never touched: a real result wins over a restored one. The loop's step
records (converge/steps/step_N.json) are restored beside the cases, with modification times in the
order the workflow made them (cases first, then each step), so that Snakemake sees them up to date.
Every published file is checked against its folder's SHA256SUMS (spreadlab/study/checksums.py) before
anything is restored from it: a table that changed since it was published is refused, naming the
file and how to get it back or re-publish it.
"""
from __future__ import annotations

import io
import json
import math
import os
import re
import time
from pathlib import Path

import pandas as pd

from spreadlab.study.checksums import sha256, verified_bytes
from spreadmap.case.identity import CASE_ID_PATTERN, LEGACY_CASE_ID_PATTERN, readable_id
from spreadmap.files import write_text_atomically
from spreadmap.loop.stepper import step_number
from spreadmap.records import CorruptFileError, read_metrics

# Columns of a results table that are the table's labels of a case, not the case's metrics.
LABEL_COLUMNS = ("sweep", "index", "k", "index_in_lattice", "name", "batch", "lds", "knob", "value", "is_base")
# Columns that come from Snakemake's benchmark of the YADE run (spreadmap.table.read_benchmark).
BENCHMARK_COLUMNS = {"benchmark_s": "s", "max_rss_mb": "max_rss"}
RESTORED = "restored.json"


class UnkeyedTableError(ValueError):
    """A published cases table whose rows cannot be restored as cases of a known scene (ids without
    a content key, or ids that do not name the row's own design point): one line naming the table
    and what to do."""


def check_case_ids(table: pd.DataFrame, table_path) -> None:
    """Refuse a table unless every row's case id is a content id (spreadmap.case.identity.CASE_ID_PATTERN)
    naming the row's own preset, design point and seed."""
    ids = table["case_id"].astype(str)
    legacy = ids.str.fullmatch(LEGACY_CASE_ID_PATTERN)
    if legacy.any():
        raise UnkeyedTableError(
            f"{table_path}: {int(legacy.sum())} of its {len(table)} cases have ids without a content key (published "
            f"before issue 35), so the material, scene and template they were run with are unknown and they are not "
            f"restored as cases of any scene; let the workflow run them, or publish the table again from a run with "
            f"content ids (tools/publish_study.py)")
    for i, (cid, row) in enumerate(zip(ids, table.to_dict("records"))):
        if not re.fullmatch(CASE_ID_PATTERN, cid):
            raise UnkeyedTableError(f"{table_path}: row {i}: {cid!r} is not a case id; the table is not restored")
        try:
            named = readable_id(row, row["preset"], int(row["seed"]))
        except (KeyError, TypeError, ValueError):
            named = None
        if not cid.startswith(f"{named}-"):
            raise UnkeyedTableError(f"{table_path}: row {i}: case id {cid} does not name the row's own preset, design "
                                    f"point and seed ({named}); the table is not restored")


def _json_value(value):
    """A table cell as the metrics.json value it came from: numpy scalars to Python, NaN (an empty
    cell) to null."""
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def case_record(row: dict) -> tuple[dict, dict]:
    """(metrics, benchmark) of one published row: the metrics without the table's labels and
    benchmark columns; the benchmark as Snakemake's column names."""
    metrics = {k: _json_value(v) for k, v in row.items() if k not in LABEL_COLUMNS and k not in BENCHMARK_COLUMNS}
    benchmark = {col: _json_value(row.get(name)) for name, col in BENCHMARK_COLUMNS.items()}
    return metrics, benchmark


def readable_metrics(path: Path) -> bool:
    """Whether a restored case's metrics.json is there and whole (a truncated one is restored again)."""
    try:
        read_metrics(path)
    except (FileNotFoundError, CorruptFileError):
        return False
    return True


WORKFLOW_CODE = ("Snakefile", "rules", "scripts")  # what Snakemake dates a job's outputs against


def restore_time(workdir: Path | str, now: float | None = None) -> float:
    """The modification time to give restored files: an hour before `now` (so that what a resumed
    run makes is newer), but newer than the workflow's own code (Snakefile, rules/, scripts/).

    Snakemake re-runs a job whose outputs are older than its script (its `code` trigger compares
    the dates), and a fresh `git clone` dates every file at the clone: restored an hour back, every
    restored case's metrics job would run again, and fail for want of the raw record.

    Parameters
    ----------
    workdir : pathlib.Path or str
        The workflow directory restored into.
    now : float or None, optional
        The time [s since the epoch]; None: the clock's.

    Returns
    -------
    float
        The time [s since the epoch]: at most `now`.
    """
    now = time.time() if now is None else float(now)
    root = Path(workdir)
    files = [root / name for name in WORKFLOW_CODE if (root / name).is_file()]
    files += [p for name in WORKFLOW_CODE if (root / name).is_dir() for p in (root / name).rglob("*") if p.is_file()]
    newest = max((p.stat().st_mtime for p in files), default=0.0)
    return min(now, max(now - 3600.0, newest + 1.0))


def restore_cases(tables: list[Path | str], workdir: Path | str, mtime: float) -> dict:
    """Write metrics.json, benchmark.tsv and restored.json of every case of the published tables.

    Under workdir/results/cases/<case_id>/ (a case in two tables once, from the first). Cases with a
    raw record are skipped, and so are cases that did not finish (status other than ok: failed,
    refused, ...), which the workflow then runs again, and cases restored before (so that running
    the tool again after a table has grown adds the new cases and leaves the rest, and their
    steps, up to date). Every table is checked (its published checksum, its case ids) before any
    case is restored.

    Parameters
    ----------
    tables : list of pathlib.Path or str
        The published cases tables (docs/study/cases_*.csv), each listed in its folder's SHA256SUMS.
    workdir : pathlib.Path or str
        The workflow directory restored into.
    mtime : float
        The modification time [s since the epoch] given to every file restored.

    Returns
    -------
    dict
        Counts: ``restored``, ``kept_real`` (a raw record there), ``duplicates`` (a case of an
        earlier table), ``not_finished`` and ``already`` (restored before).

    Raises
    ------
    spreadlab.study.checksums.PublishedFileError
        If a table does not match its published checksum or no manifest lists it.
    UnkeyedTableError
        If a table's case ids have no content key or do not name the row's own preset, design
        point and seed.
    ValueError
        If a table has no ``case_id`` column.
    """
    workdir = Path(workdir)
    counts = {"restored": 0, "kept_real": 0, "duplicates": 0, "not_finished": 0, "already": 0}
    seen = set()
    checked = []  # every table checked against its published checksum before any case is restored
    for table_path in tables:
        data = verified_bytes(table_path)
        table = pd.read_csv(io.BytesIO(data))
        if "case_id" not in table.columns:
            raise ValueError(f"{table_path}: not a cases table (no case_id column)")
        check_case_ids(table, table_path)
        checked.append((table_path, table, sha256(data)))
    for table_path, table, sha in checked:
        for i, row in enumerate(table.to_dict("records")):
            cid = row["case_id"]
            if cid in seen:
                counts["duplicates"] += 1
                continue
            seen.add(cid)
            folder = workdir / "results" / "cases" / cid
            if (folder / "raw.json").exists():
                counts["kept_real"] += 1
                continue
            if (folder / RESTORED).exists() and readable_metrics(folder / "metrics.json"):
                # restored before: left as it is (a new mtime would make the steps after it stale)
                counts["already"] += 1
                continue
            if row.get("status") != "ok":  # a case that did not finish gets a new try on this machine
                counts["not_finished"] += 1
                continue
            metrics, benchmark = case_record(row)
            files = {
                "metrics.json": json.dumps(metrics, indent=1) + "\n",
                "benchmark.tsv": "\t".join(benchmark) + "\n"
                                 + "\t".join("NA" if v is None else repr(v) for v in benchmark.values()) + "\n",
                RESTORED: json.dumps({"restored_from": str(table_path), "table_sha256": sha, "row": i,
                                      "note": "metrics and benchmark from a published cases table; the raw "
                                              "YADE record is not kept. Delete this folder to re-run the case."},
                                     indent=1) + "\n",
            }
            for name, text in files.items():
                write_text_atomically(folder / name, text)
                os.utime(folder / name, (mtime, mtime))
            counts["restored"] += 1
    return counts


def restore_steps(steps: list[Path | str], workdir: Path | str, mtime: float) -> list[str]:
    """Copy the loop's step records to workdir/results/converge/, each a second newer than the one before it.

    And newer than the cases, restored at `mtime`. An existing step is left alone. Every record is
    checked against its published checksum before any is copied.

    Parameters
    ----------
    steps : list of pathlib.Path or str
        The published step records (converge/steps/step_N.json).
    workdir : pathlib.Path or str
        The workflow directory restored into.
    mtime : float
        The cases' modification time [s since the epoch]; the k-th step by n gets mtime + k.

    Returns
    -------
    list of str
        The names of the step records written.

    Raises
    ------
    spreadlab.study.checksums.PublishedFileError
        If a record does not match its published checksum or no manifest lists it.
    """
    out = []
    texts = {path: verified_bytes(path).decode() for path in steps}  # all checked before any is restored
    for k, path in enumerate(sorted(steps, key=step_number), start=1):
        target = Path(workdir) / "results" / "converge" / Path(path).name
        if target.exists():
            continue
        write_text_atomically(target, texts[path])
        os.utime(target, (mtime + k, mtime + k))
        out.append(target.name)
    return out
