"""The results table: one row per case (parameters, MFR, PD, regime, flags, the reason a case did
not finish (with its log's verdict), diagnostics, preset, wall time and peak memory from
Snakemake's benchmark, then the case's noise estimate and its layer quality, then its floor and
its effective gap), and the run summary built from it."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .case.substrate import effective_gap_um
from .design import NAMES
from .files import atomic_path
from .metrics import NEW_COLUMNS
from .records import current_columns, read_metrics

FIRST_COLUMNS = ["case_id", "sweep", "index", *NAMES, "preset", "seed", "status",
                 "mfr", "pd", "regime", "flagged", "flag_reason", "reason"]
# after every other column (added later than the rest): noise estimate and layer quality
LAST_COLUMNS = list(NEW_COLUMNS)
# last of all, where the cases' metrics name their floor (spreadmap.case.substrate): the floor, a rough
# substrate's jitter, and the gap measured over it: h on a flat floor, h + the substrate's mean
# hollow depth on a rough one (README, "The model": two gaps)
FLOOR_COLUMNS = ["substrate", "substrate_jitter", "h_eff_um", "h_eff_over_d"]


def flagged(table: pd.DataFrame) -> np.ndarray:
    """Rows flagged by a stability bound (none when the column is absent or empty)."""
    if "flagged" not in table.columns:
        return np.zeros(len(table), dtype=bool)
    return table["flagged"].fillna(False).astype(bool).to_numpy()


def usable(table: pd.DataFrame, columns=()) -> np.ndarray:
    """The one rule of a usable case: finished (status ok) and not flagged by a stability bound,
    and, for each of `columns` given, a finite value.

    Every reader of the table takes its cases through this rule (the surrogate's training rows,
    the loop's map model, the maps, the study rule, the noise law, the fidelity factors); a column
    ``status`` or ``flagged`` that is absent imposes nothing.

    Parameters
    ----------
    table : pandas.DataFrame
        The results table (one row per case); ``status`` and ``flagged`` are read if present.
    columns : iterable of str, optional
        Columns that must hold a finite number (e.g. the targets a model is fitted on, the
        design's inputs); text and empty cells count as not finite. Default: none.

    Returns
    -------
    numpy.ndarray
        Boolean mask, one entry per row of `table`.

    Raises
    ------
    ValueError
        If a column of `columns` is not in `table`; the message names it.
    """
    columns = list(columns)
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ValueError(f"usable cases: the results table lacks column(s) {missing}")
    ok = ~flagged(table)
    if "status" in table.columns:
        ok &= (table["status"] == "ok").to_numpy()
    for c in columns:
        ok &= np.isfinite(pd.to_numeric(table[c], errors="coerce").to_numpy(float))
    return ok


def usable_cases(table: pd.DataFrame, columns=()) -> pd.DataFrame:
    """The rows of a results table that ``usable`` keeps, in their order.

    Parameters
    ----------
    table : pandas.DataFrame
        The results table (one row per case).
    columns : iterable of str, optional
        Columns that must hold a finite number (``usable``); default: none.

    Returns
    -------
    pandas.DataFrame
        The usable rows, with `table`'s index and columns.
    """
    return table[usable(table, columns)]


def partition(table: pd.DataFrame, n: int, sweep: str | None = "lds", order_col: str = "index") -> pd.DataFrame:
    """The one partition of a sequence: its first n cases, the rows of `sweep` whose `order_col`
    is below n (LDS-n), in that order.

    Parameters
    ----------
    table : pandas.DataFrame
        A results table.
    n : int
        The partition's size: the cases of positions 0 .. n-1 of the sequence.
    sweep : str or None, optional
        Only the rows of this sweep (where the table has a ``sweep`` column); None: every row.
    order_col : str, optional
        The column holding each case's position in the sequence (0-based).

    Returns
    -------
    pandas.DataFrame
        The partition's rows (all of them, usable or not), sorted by `order_col`, index reset.
    """
    rows = table
    if sweep is not None and "sweep" in table.columns:
        rows = rows[rows["sweep"].astype(str) == sweep]
    rows = rows[rows[order_col].astype(int) < int(n)]
    return rows.sort_values(order_col, kind="stable").reset_index(drop=True)


def read_benchmark(path: Path | str) -> dict:
    """Wall time (s) and peak resident memory (MB) of the YADE run, from Snakemake's benchmark file."""
    try:
        row = pd.read_csv(path, sep="\t").iloc[-1]
        return {"benchmark_s": float(row["s"]), "max_rss_mb": float(row["max_rss"])}
    except (OSError, KeyError, IndexError, ValueError, pd.errors.EmptyDataError):
        return {"benchmark_s": float("nan"), "max_rss_mb": float("nan")}


def build_table(metrics_files, benchmark_files, labels: list[dict]) -> pd.DataFrame:
    """The results table of the cases' metrics records, one row per case.

    labels[i] = {"sweep": ..., "index": ...} for metrics_files[i]. A metrics file that is not a
    whole metrics record raises spreadmap.records.CorruptFileError naming it.

    Parameters
    ----------
    metrics_files : sequence of pathlib.Path or str
        The cases' metrics.json files.
    benchmark_files : sequence of pathlib.Path or str
        Snakemake's benchmark file of each case's YADE run, same order; one that cannot be read
        gives NaN wall time (``benchmark_s``, s) and peak memory (``max_rss_mb``, MB).
    labels : list of dict
        Columns to add to each row, same order: ``{"sweep": ..., "index": ...}``.

    Returns
    -------
    pandas.DataFrame
        ``FIRST_COLUMNS`` first, the other columns of the records, then the noise and layer
        columns and (where the records name their floor) ``FLOOR_COLUMNS`` with the effective
        gap; a target a record names by its old name under its name now
        (``spreadmap.records.current_columns``). With no files: an empty table with ``FIRST_COLUMNS``.

    Raises
    ------
    spreadmap.records.CorruptFileError
        If a metrics file is not a whole metrics record.
    """
    rows = []
    for mfile, bfile, label in zip(metrics_files, benchmark_files, labels):
        row = read_metrics(mfile)  # a truncated or damaged record: CorruptFileError, never a row
        row.update(label)
        row.update(read_benchmark(bfile))
        rows.append(row)
    table = current_columns(pd.DataFrame(rows))  # a record of an earlier run may name a target by its old name
    if table.empty:
        return pd.DataFrame(columns=FIRST_COLUMNS)
    table = with_effective_gap(table)
    last = [c for c in LAST_COLUMNS + FLOOR_COLUMNS if c in table.columns]
    return table[FIRST_COLUMNS + [c for c in table.columns if c not in FIRST_COLUMNS + last] + last]


def with_effective_gap(table: pd.DataFrame) -> pd.DataFrame:
    """The table with h_eff_um and h_eff_over_d (spreadmap.case.substrate.effective_gap_um) where its
    rows name their floor (a `substrate` column; NaN in a row whose floor is unknown); as it is
    where they do not (tables of metrics from before the floor was recorded)."""
    if "substrate" not in table.columns:
        return table
    jitter = table["substrate_jitter"] if "substrate_jitter" in table.columns else np.nan
    h_eff = [effective_gap_um(h, d, kind, j) for h, d, kind, j in
             zip(table["h_um"], table["d_um"], table["substrate"], np.broadcast_to(jitter, len(table)))]
    return table.assign(h_eff_um=h_eff, h_eff_over_d=np.asarray(h_eff, float) / table["d_um"].to_numpy(float))


def write_table(table: pd.DataFrame, path: Path | str) -> None:
    """Write a table as CSV (no index column), atomically (``spreadmap.files.atomic_path``).

    Parameters
    ----------
    table : pandas.DataFrame
        The table to write.
    path : pathlib.Path or str
        The CSV file; replaced whole or not at all (its folder is made if missing).

    Raises
    ------
    OSError
        If the file cannot be written; a full disk or a file-size limit names `path`.
    """
    with atomic_path(path) as tmp:
        table.to_csv(tmp, index=False)
