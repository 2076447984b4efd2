"""Which rows of a results table the surrogate learns from, and what it knows of their noise.

The rows are the usable cases of ``table.usable`` (finished, not flagged, finite inputs and
targets); a partition is ``table.partition``. Every excluded row is counted by reason; nothing
is dropped silently.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..design import NAMES
from ..table import flagged, usable

SD_SUFFIX = "_sd"


@dataclass
class TrainingRows:
    """The usable cases: inputs X (n, 4) in NAMES order, targets and, where the table has a
    ``<target>_sd`` column, each case's own noise SD (NaN where a case lacks it)."""

    frame: pd.DataFrame
    targets: list
    exclusions: dict

    @property
    def X(self) -> np.ndarray:
        return self.frame[list(NAMES)].to_numpy(float)

    def y(self, target: str) -> np.ndarray:
        return self.frame[target].to_numpy(float)

    def sd(self, target: str) -> np.ndarray | None:
        """Per-case noise SD of ``target`` if the table carries it (None otherwise)."""
        col = target + SD_SUFFIX
        if col not in self.frame:
            return None
        sd = pd.to_numeric(self.frame[col], errors="coerce").to_numpy(float)
        return sd if np.isfinite(sd).any() else None

    def __len__(self) -> int:
        return len(self.frame)


def select(df: pd.DataFrame, targets) -> TrainingRows:
    """The usable rows of a results table for these targets, and the excluded ones by reason.

    Reasons, each row counted once in this order: its status if not ``ok`` (``failed``, ...),
    ``flagged`` (a stability bound broken), ``nonfinite`` (an input or a target NaN or inf).
    """
    required = ["case_id", "status", *NAMES, *targets]
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise ValueError(f"results table lacks column(s) {missing}")
    ids = df["case_id"].astype(str)
    dup = ids[ids.duplicated()].unique()
    if len(dup):
        raise ValueError(f"duplicate case_id(s) in the results table: {list(dup[:5])}")
    values = df[[*NAMES, *targets]].apply(pd.to_numeric, errors="coerce").to_numpy(float)
    finite = np.isfinite(values).all(axis=1)
    ok_status = (df["status"].astype(str).str.strip() == "ok").to_numpy()
    keep = usable(df, (*NAMES, *targets))
    exclusions = {}
    for status, n in df.loc[~ok_status, "status"].astype(str).value_counts().items():
        exclusions[status] = int(n)
    exclusions["flagged"] = int((ok_status & flagged(df)).sum())
    exclusions["nonfinite"] = int((ok_status & ~flagged(df) & ~finite).sum())
    frame = df.loc[keep].copy()
    frame["case_id"] = frame["case_id"].astype(str)
    for c in (*NAMES, *targets):
        frame[c] = pd.to_numeric(frame[c]).astype(float)
    return TrainingRows(frame.reset_index(drop=True), list(targets), exclusions)
