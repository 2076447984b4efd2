"""The loop's figure: the path of ``snakemake converge``, each map criterion against its threshold at
every batch beside the study's rule (PNG, PDF and CSV by ``figures.save_figure``)."""
from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np
import pandas as pd

from ..figures import N_LABEL, new_figure, save_figure
from ..study_rule import rule as cv

# ----------------------------------------------------------------------------------------------
# the path of `snakemake converge`
# ----------------------------------------------------------------------------------------------
CRITERION_LABELS = {"map_error": "map error / tolerance (the larger of CV net of noise, posterior)",
                    "cv_rmse": "CV RMSE / (factor x noise SD)",
                    "map_change": "map change / (fraction x noise SD)",
                    "ci": "CI half-width / tolerance (worst statistic)"}


def plot_converge_path(record: Mapping, path_stem) -> dict[str, Path]:
    """Each map criterion's value (ratio to its threshold: <= 1 holds) at every batch, the
    study's rule (its largest change / its tolerance) beside them, and why the run stopped.

    Parameters
    ----------
    record : Mapping
        The last step record of ``snakemake converge`` (``spreadmap.loop.stepper.step``): its
        ``criteria`` (``path``, ``stop_on``), ``study_rule_path``, ``study_rule_tolerance``,
        ``reason`` and ``n`` are read.
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv`` (the ratios plotted).

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    path = record["criteria"]["path"]
    rows = []
    for h in path:
        for c in CRITERION_LABELS:
            if h.get(c):
                rows.append({"n": h["n"], "criterion": c, "ratio": h[c]["value"], "holds": h[c]["holds"]})
    tol = float(record.get("study_rule_tolerance", cv.DEFAULT_TOLERANCE))
    for h in record.get("study_rule_path", []):
        if h.get("max_change") is not None and np.isfinite(h["max_change"]):
            rows.append({"n": h["n"], "criterion": "study_rule", "ratio": h["max_change"] / tol,
                         "holds": h["max_change"] < tol})
    data = pd.DataFrame(rows, columns=["n", "criterion", "ratio", "holds"])
    fig = new_figure(7.0, 4.4)
    ax = fig.subplots()
    labels = {**CRITERION_LABELS, "study_rule": f"study's rule: largest change / {tol:g} (reported)"}
    for i, (c, lab) in enumerate(labels.items()):
        g = data[data["criterion"] == c]
        if g.empty:
            continue
        req = c in record["criteria"]["stop_on"]
        ax.plot(g["n"], g["ratio"], marker="o", ms=4, color=f"C{i}", ls="-" if req else "--",
                label=lab + ("" if req or c == "study_rule" else " (not required)"))
    ax.axhline(1.0, color="k", lw=1)
    ax.set_yscale("log")
    ax.set_xlabel(N_LABEL)
    ax.set_ylabel("criterion / its threshold [-] (<= 1 holds)")
    ax.set_title(f"converge: {record['reason']} after {record['n']} cases", fontsize="small")
    ax.legend(fontsize="x-small")
    ax.grid(True, alpha=0.3)
    return save_figure(fig, path_stem, data)
