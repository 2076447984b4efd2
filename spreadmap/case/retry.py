"""Failed cases retried on request: list a workflow directory's failed cases, move a failed run
aside, and the Snakemake command that runs the cases again (tools/retry_failed.py).

A case that fails on every attempt (rules/simulate.smk: a crash or a timeout, retried once; the
YADE script's own failed check, at once) leaves a raw record of status ``failed`` in
``results/cases/<case>/raw.json``, and Snakemake takes that record for the case's output: it stays
failed. Archiving moves the files of that run (``RUN_FILES``: the record, the run's log and
benchmark, the metrics made from the record) into ``results/cases/<case>/failed-<n>/``, the first
free n, inside the case's own folder (so that a listing of ``results/cases/*/raw.json`` sees no
second case, and migrating the case's id takes its archive along). The rendered script
(``case.py``) stays: the case is the same case, under the same id. Snakemake does not re-make a
missing file whose consumers (the tables) are up to date, so the run is asked for by name:
``--forcerun`` of the archived records (``rerun_command``), which also re-makes what follows from
them. Refused cases (status ``refused``) are not listed: a refusal is decided by the parameters
and would recur.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..records import CorruptFileError, read_raw

RUN_FILES = ("raw.json", "run.log", "benchmark.tsv", "metrics.json", "metrics.log")
ARCHIVE_PREFIX = "failed-"


@dataclass(frozen=True)
class FailedCase:
    """A case whose raw record says ``failed``: its id, folder and the record's reason."""

    case_id: str
    folder: Path
    reason: str


def failed_cases(workdir: Path | str) -> list[FailedCase]:
    """The failed cases of a workflow directory, by case id.

    Parameters
    ----------
    workdir : pathlib.Path or str
        The workflow directory (the one holding ``results/cases``).

    Returns
    -------
    list of FailedCase
        One per case folder whose ``raw.json`` is a raw record of status "failed", sorted by id.
        A damaged record is not listed (the workflow moves it aside and runs the case again).

    Raises
    ------
    FileNotFoundError
        If ``workdir/results/cases`` does not exist.
    """
    cases = Path(workdir) / "results" / "cases"
    if not cases.is_dir():
        raise FileNotFoundError(f"{cases}: no such folder (is {workdir} a workflow directory that has run cases?)")
    out = []
    for raw_path in sorted(cases.glob("*/raw.json")):
        try:
            raw = read_raw(raw_path)
        except CorruptFileError:
            continue
        if raw["status"] == "failed":
            out.append(FailedCase(raw_path.parent.name, raw_path.parent, str(raw.get("reason") or "no reason recorded")))
    return out


def snakemake_running(workdir: Path | str) -> bool:
    """Whether a Snakemake run holds the workflow directory (a lock file in ``.snakemake/locks``)."""
    locks = Path(workdir) / ".snakemake" / "locks"
    return locks.is_dir() and any(locks.iterdir())


def archive_run(case: FailedCase) -> Path:
    """Move the failed run's files (``RUN_FILES`` that exist) into ``<case folder>/failed-<n>/``.

    Parameters
    ----------
    case : FailedCase
        The case (``failed_cases``).

    Returns
    -------
    pathlib.Path
        The archive folder written.

    Raises
    ------
    ValueError
        If the case's ``raw.json`` is no longer a failed record (run again, or archived already).
    """
    raw_path = case.folder / "raw.json"
    try:
        status = read_raw(raw_path)["status"] if raw_path.exists() else "missing"
    except CorruptFileError:
        status = "damaged"
    if status != "failed":
        raise ValueError(f"{case.case_id}: its raw.json is {status}, not a failed record; nothing archived")
    n = 1
    while (case.folder / f"{ARCHIVE_PREFIX}{n}").exists():
        n += 1
    archive = case.folder / f"{ARCHIVE_PREFIX}{n}"
    archive.mkdir()
    # the record last: until it has moved, the case still reads as failed and can be archived again
    for name in sorted(RUN_FILES, key=lambda name: name == "raw.json"):
        if (case.folder / name).exists():
            (case.folder / name).rename(archive / name)
    return archive


def rerun_command(cases: list[FailedCase], target: str = "TARGET") -> str:
    """The Snakemake command that runs archived cases again, and what follows from them.

    Parameters
    ----------
    cases : list of FailedCase
        The archived cases.
    target : str, optional
        The command's target (``sweeps``, ``converge``, ...); default a placeholder.

    Returns
    -------
    str
        ``snakemake <target> --forcerun results/cases/<case>/raw.json ...``.
    """
    return " ".join(["snakemake", target, "--forcerun", *(f"results/cases/{c.case_id}/raw.json" for c in cases)])
