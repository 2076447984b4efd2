"""What a case will cost before it runs: a model of ln(CPU seconds) over the design space, fitted on
the run's own finished cases, for the acquisition that spends CPU where it buys the most map
(``active``'s ``ivr_per_cpu``).

Why a GP of ln CPU (the map model's ``make_gp_fit``, on the same unit cube): a case's CPU is set by
its spheres and steps, which the scene derives from h/d (the pile's standing reserve grows as
h^2, so the spheres as (h/d)^2 and more), v (the travel time) and the window (longer at small
h/d); on this scene it spans 25-1350 s over the design space (docs/study), ln CPU is smooth in
the inputs (a quadratic in ln(h/d) with f, ln d, ln v leaves a residual SD of 0.19 on 60 cases of
the default scene) and the GP needs no hand-chosen features. The cost predicted is
exp(mean + var / 2), the mean of a log-normal.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import pandas as pd

from ..design import NAMES
from .model import FitFunction, make_gp_fit

MIN_CASES = 5  # finished cases with a CPU time a cost model needs


def finished_costs(table: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """(X in NAMES order, CPU seconds) of the rows that finished (status ok) with a CPU time > 0."""
    cpu = pd.to_numeric(table.get("cpu_time", pd.Series(np.nan, index=table.index)), errors="coerce").to_numpy(float)
    ok = (table["status"].astype(str).str.strip() == "ok").to_numpy() & np.isfinite(cpu) & (cpu > 0)
    return table.loc[ok, list(NAMES)].to_numpy(float), cpu[ok]


def fit_cost(table: pd.DataFrame, ranges: dict | None = None, fit: FitFunction | None = None) -> Callable[[np.ndarray], np.ndarray]:
    """cost(X) -> predicted CPU seconds of cases at X (physical units, NAMES order), from the
    finished cases of ``table``. Raises ValueError with fewer than MIN_CASES of them."""
    X, cpu = finished_costs(table)
    if len(cpu) < MIN_CASES:
        raise ValueError(f"a cost model needs {MIN_CASES} finished cases with a CPU time; the table has {len(cpu)}")
    model = (fit or make_gp_fit(ranges))(X, np.log(cpu))

    def cost(points: np.ndarray) -> np.ndarray:
        mean, sd = model.predict(np.asarray(points, float), return_std=True)
        return np.exp(mean + 0.5 * (sd**2 + model.noise_sd**2))

    return cost
