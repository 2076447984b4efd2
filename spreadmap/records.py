"""Reading the workflow's own files so that a damaged one is never read as data.

The workflow writes its files atomically (spreadmap/files.py), so a run killed half-way leaves
the old file or the new one. A file can still be damaged from outside: a copy cut short, a disk
that lost blocks, an edit by hand. Each reader here checks what a whole file of its kind must be
(a raw record or a metrics record: a JSON object with its keys; a table: every row as long as the
header, ending with a line break) and raises CorruptFileError, naming the file and why, instead
of returning what it could parse.

Under Snakemake (`spreadmap.logs.log_to` installs `remake_when_corrupt`) a job that meets such a
file moves it aside (<name>.corrupt, kept to look at) and ends with that one line; the next
`snakemake` sees the file missing and re-makes it with the rule that made it, so that it is
re-made, not read.
"""
from __future__ import annotations

import csv
import io
import json
import os
import sys
from pathlib import Path

from .targets import current_name

RAW_FORMAT = "spreadmap-raw"


class CorruptFileError(ValueError):
    """A file that is there but is not a whole file of its kind. `remakeable`: a rule of the
    workflow makes it, so moving it aside makes the next run re-make it."""

    def __init__(self, path: Path | str, message: str, remakeable: bool = True):
        super().__init__(message)
        self.path = Path(path)
        self.remakeable = remakeable


def _text(path: Path, what: str) -> str:
    data = path.read_bytes()  # a missing file raises FileNotFoundError: missing is not corrupt
    if not data.strip():
        raise CorruptFileError(path, f"{path}: empty {what} ({len(data)} bytes); not read as data")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise CorruptFileError(path, f"{path}: {what} is not UTF-8 text (corrupted at byte {error.start}); "
                                     "not read as data") from None


def read_json_object(path: Path | str, what: str, required=()) -> dict:
    """A JSON object with the `required` keys, else CorruptFileError naming the file and why.

    Parameters
    ----------
    path : pathlib.Path or str
        The JSON file.
    what : str
        What the file is, for the error message (e.g. "metrics record").
    required : iterable of str, optional
        Keys the object must have.

    Returns
    -------
    dict
        The parsed JSON object.

    Raises
    ------
    FileNotFoundError
        If the file is missing (missing is not corrupt).
    CorruptFileError
        If the file is empty, not UTF-8, not valid JSON (truncated or corrupted), not a JSON
        object, or lacks a `required` key.
    """
    path = Path(path)
    text = _text(path, what)
    try:
        record = json.loads(text)
    except json.JSONDecodeError as error:
        ends = error.pos >= len(text.rstrip()) or error.msg.startswith("Unterminated string")
        why = "truncated: the file ends before its JSON does" if ends else "corrupted"
        raise CorruptFileError(path, f"{path}: {what} is not valid JSON, {why} ({error.msg}, line {error.lineno} "
                                     f"column {error.colno}); not read as data") from None
    if not isinstance(record, dict):
        raise CorruptFileError(path, f"{path}: {what} is not a JSON object (a {type(record).__name__}); "
                                     "not read as data")
    missing = [k for k in required if k not in record]
    if missing:
        raise CorruptFileError(path, f"{path}: {what} lacks {', '.join(missing)}; not read as data")
    return record


def read_raw(path: Path | str) -> dict:
    """A case's raw YADE record (raw.json / simulated.json).

    Parameters
    ----------
    path : pathlib.Path or str
        The record's file.

    Returns
    -------
    dict
        The record: a JSON object with at least ``format`` (starting "spreadmap-raw"),
        ``status`` and ``params``.

    Raises
    ------
    FileNotFoundError
        If the file is missing.
    CorruptFileError
        If it is not such a record (see ``read_json_object``) or its format is not a raw
        record's.
    """
    raw = read_json_object(path, "raw YADE record", ("format", "status", "params"))
    if not str(raw["format"]).startswith(RAW_FORMAT):
        raise CorruptFileError(path, f"{path}: not a raw YADE record (format {raw['format']!r}); not read as data")
    return raw


def read_metrics(path: Path | str) -> dict:
    """A case's metrics record (metrics.json).

    Parameters
    ----------
    path : pathlib.Path or str
        The record's file.

    Returns
    -------
    dict
        The record: a JSON object with at least ``case_id`` and ``status``.

    Raises
    ------
    FileNotFoundError
        If the file is missing.
    CorruptFileError
        If it is not a whole metrics record (see ``read_json_object``).
    """
    return read_json_object(path, "metrics record", ("case_id", "status"))


def read_table(path: Path | str):
    """A CSV table the workflow wrote (pandas `to_csv`), refused if damaged.

    Refused if it does not end with a line break or a row's field count differs from the
    header's (a table cut off mid-row); else what pd.read_csv reads from it, its columns under
    their names now (``current_columns``: a table written before a target was renamed reads as
    one written after). A table cut exactly at a line break has whole rows and passes: the atomic
    writer is what rules that out.

    Parameters
    ----------
    path : pathlib.Path or str
        The CSV file.

    Returns
    -------
    pandas.DataFrame
        The table as ``pd.read_csv`` reads it, old target names renamed (``current_columns``).

    Raises
    ------
    FileNotFoundError
        If the file is missing.
    CorruptFileError
        If the file is empty, not UTF-8, does not end with a line break, has a row whose field
        count differs from the header's, or is not CSV.
    """
    path = Path(path)
    text = _text(path, "table")
    if not text.endswith("\n"):
        raise CorruptFileError(path, f"{path}: the table ends mid-row (no line break at its end: half-written); "
                                     "not read as data")
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next(reader)
        for fields in reader:
            if fields and len(fields) != len(header):
                raise CorruptFileError(path, f"{path}: row {reader.line_num} has {len(fields)} fields, the header "
                                             f"{len(header)} (half-written or corrupted); not read as data")
    except csv.Error as error:
        raise CorruptFileError(path, f"{path}: not a CSV table ({error}, line {reader.line_num}); "
                                     "not read as data") from None
    import pandas as pd  # here: the YADE job's environment reads raw records without pandas

    return current_columns(pd.read_csv(io.StringIO(text)))


def current_columns(table):
    """A table with the columns of a renamed target under its name now (``targets.RENAMED``:
    ``layer_packing`` and ``layer_packing_sd`` read as ``layer_fill`` and ``layer_fill_sd``).

    The one place a table written under an old name (a published cases table, a metrics record of
    an earlier run) is read as a current one; ``read_table`` and ``spreadmap.table.build_table``
    call it, and so do the tools that read published tables. Quiet: the values are the same
    measure, only the name changed.

    Parameters
    ----------
    table : pandas.DataFrame
        A table (not changed).

    Returns
    -------
    pandas.DataFrame
        `table` itself if no column has an old name; else a copy with each old column renamed, or,
        where the new column is there too (records of both ages in one table), merged into it:
        the new column's value, the old one's where the new one is missing.
    """
    renames = {c: current_name(c) for c in table.columns if current_name(c) != c}
    if not renames:
        return table
    out = table.copy()
    for old, new in renames.items():
        if new in out.columns:
            out[new] = out[new].combine_first(out[old])
            out = out.drop(columns=old)
        else:
            out = out.rename(columns={old: new})
    return out


def quarantine(path: Path | str) -> Path:
    """Move a damaged file aside to <name>.corrupt (replacing an older one); returns where."""
    path = Path(path)
    moved = path.with_name(path.name + ".corrupt")
    os.replace(path, moved)
    return moved


def remake_when_corrupt() -> None:
    """Install the hook of a Snakemake job: an uncaught CorruptFileError of a file a rule makes
    moves the file aside and ends the job with one line saying so (exit status 1); anything else
    goes to the usual hook (a traceback)."""
    previous = sys.excepthook

    def hook(kind, error, tb):
        if isinstance(error, CorruptFileError) and error.remakeable and error.path.exists():
            moved = quarantine(error.path)
            print(f"spreadmap: {error}. Moved it aside to {moved}; run snakemake again: it re-makes "
                  f"{error.path} with the rule that made it.", file=sys.stderr)
        else:
            previous(kind, error, tb)

    sys.excepthook = hook
