"""The results table: one row per case (parameters, MFR, PD, regime, flags, the reason a case did
not finish (with its log's verdict), diagnostics, preset, wall time and peak memory from
Snakemake's benchmark, then the case's noise estimate and its layer quality, then its floor and
its effective gap), and the run summary built from it."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .case.substrate import effective_gap_um
from .files import atomic_path
from .metrics import NEW_COLUMNS
from .records import read_metrics

FIRST_COLUMNS = ["case_id", "sweep", "index", "f", "d_um", "h_um", "v_mm_s", "preset", "seed", "status",
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


def usable(table: pd.DataFrame) -> np.ndarray:
    """Rows fit for statistics and training: finished (status ok) and not flagged by a stability
    bound.

    Columns that are absent impose nothing.

    Parameters
    ----------
    table : pandas.DataFrame
        The results table (one row per case); ``status`` and ``flagged`` are read if present.

    Returns
    -------
    numpy.ndarray
        Boolean mask, one entry per row of `table`.
    """
    ok = ~flagged(table)
    if "status" in table.columns:
        ok &= (table["status"] == "ok").to_numpy()
    return ok


def usable_cases(table: pd.DataFrame) -> pd.DataFrame:
    """The rows of a results table that ``usable`` keeps (finished, not flagged), in their order.

    Parameters
    ----------
    table : pandas.DataFrame
        The results table (one row per case).

    Returns
    -------
    pandas.DataFrame
        The usable rows, with `table`'s index and columns.
    """
    return table[usable(table)]


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
        gap. With no files: an empty table with ``FIRST_COLUMNS``.

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
    table = pd.DataFrame(rows)
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
