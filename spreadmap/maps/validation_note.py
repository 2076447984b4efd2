"""The line a map of a model writes under its title: how that model validated against the noise.

The numbers are the surrogate's validation table (``surrogate_metrics.csv``, written by
``spreadmap.surrogate.fitting.validate_surrogate``): per target and model the repeated k-fold
RMSE of cases no fold model saw, over the RMS noise SD of one run. A map drawn from a model that is
not the one the maps use (the MLP ensemble beside the GP) says so, and how it compared.
"""
from __future__ import annotations

import pandas as pd

from ..targets import short

MODEL_NAMES = {"gp": "GP", "mlp": "MLP ensemble"}


def validation_note(validation: pd.DataFrame, kind: str, targets, n_cases: int | None = None,
                    other: str | None = None) -> str:
    """Two lines: which model, then its cross-validated RMSE over one run's noise SD for each of `targets`.

    Parameters
    ----------
    validation : pandas.DataFrame
        The validation table: one row per (``target``, ``model``) with ``rmse``, ``noise_sd``,
        ``rmse_over_noise`` and ``n_cases`` (surrogate_metrics.csv read back).
    kind : str
        The model the map is drawn from (``gp`` or ``mlp``).
    targets : sequence of str
        The targets the map draws, in the order named.
    n_cases : int or None, optional
        The usable cases the map's model was trained on; where given, the validation must have
        been run on as many (else it is another table's).
    other : str or None, optional
        Another model whose ratios are given beside, for comparison (e.g. ``gp``); None: none.

    Returns
    -------
    str
        E.g. "Drawn from the MLP ensemble: its CV RMSE / one run's noise SD over 125 cases (k-fold,
        3 repeats):" and, after a line break, "MFR 2.44 (0.0246 / 0.0101), PD 2.36 (0.0245 /
        0.0104); the GP's 1.85, 1.80".

    Raises
    ------
    ValueError
        If the table lacks a row of `kind` (or of `other`) for a target, holds two, or was run on
        another number of cases than `n_cases`.
    """
    targets = list(targets)

    def row(target: str, model: str) -> pd.Series:
        rows = validation[(validation["target"] == target) & (validation["model"] == model)]
        if len(rows) != 1:
            raise ValueError(f"the validation table has {len(rows)} rows of model {model!r} for target {target!r} "
                             f"(one expected)")
        return rows.iloc[0]

    rows = [row(t, kind) for t in targets]
    n = {int(r["n_cases"]) for r in rows}
    if len(n) != 1 or (n_cases is not None and n != {int(n_cases)}):
        raise ValueError(f"the validation ran on {sorted(n)} cases, the map's model on {n_cases}: "
                         f"not this table's validation")
    k = int(rows[0]["repeats"]) if "repeats" in validation else None
    repeats = "" if k is None else f", {k} repeat{'s' if k != 1 else ''}"
    ratios = ", ".join(f"{short(t)} {r['rmse_over_noise']:.2f} ({r['rmse']:.3g} / {r['noise_sd']:.3g})"
                       for t, r in zip(targets, rows))
    text = (f"Drawn from the {MODEL_NAMES.get(kind, kind)}: its CV RMSE / one run's noise SD over {n.pop()} cases "
            f"(k-fold{repeats}):\n{ratios}")
    if other is not None:
        theirs = ", ".join(f"{float(row(t, other)['rmse_over_noise']):.2f}" for t in targets)
        text += f"; the {MODEL_NAMES.get(other, other)}'s {theirs}"
    return text
