"""What a case will cost before it runs: a law of the spheres and the steps the scene plans.

Why a law of the plan, not of this run's clock
----------------------------------------------
The loop's batches go where a case buys the most map per CPU-second (``active``'s
``ivr_per_cpu``). When the cost came from a model fitted on the run's own measured ``cpu_time``,
a repeated or resumed run picked other cases (the machine's speed changes between sessions and
with load: 6 of 16 cases differed after a resume). A case's CPU is set by what the scene plans
for it, ``case.scene.scene_parameters``: its sphere count N and its estimated steps S, both known
before it runs and the same on every machine. The law is

    CPU [s] = exp(ln_a) * N^b_particles * S^b_steps

with exponents fitted once on the published cases (``fit_law``; docs/replay/cost_law.json): the
contact loop's cost per sphere-step grows with the pile (N^1.092 with S^1.324 over 1,041 published
cases, the planned steps overestimating the run's by ~1.5x at the thin gaps where the window
closes early). The acquisition divides by the *relative* cost of a candidate (against the median
candidate's), so only the exponents decide the batch; ``ln_a`` scales the absolute CPU that the
modelled budget and the replay count, and ``calibrated`` rescales it to this machine's measured
cases for estimates of the CPU still to go.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Mapping

import numpy as np
import pandas as pd

from ..design import NAMES
from ..schema import checked

DEFAULT_LAW = checked("converge")["cost_law"]  # the schema's converge.cost_law, for a config without one


def planned_work(points: np.ndarray, config: Mapping, preset: str) -> np.ndarray:
    """(N spheres, estimated steps) the scene plans for each design point (physical, NAMES order)."""
    from ..case.scene import scene_parameters

    out = np.empty((len(points), 2))
    for i, p in enumerate(np.asarray(points, float)):
        params = scene_parameters(dict(zip(NAMES, map(float, p))), preset, dict(config), "cost")
        out[i] = params["n_particles"], params["estimated_steps"]
    return out


@dataclass
class PlannedCost:
    """cost(X) -> CPU seconds of cases at physical points X, from the scene's plan and the law.

    CPU [s] = exp(ln_a) * N^b_particles * S^b_steps, with N the spheres and S the estimated steps
    that ``case.scene.scene_parameters`` plans for the case (see the module's docstring for why
    a law of the plan and not of this run's clock). Calling the instance on points X (shape
    (n, 4), physical units, ``design.NAMES`` order) returns their CPU seconds, shape (n,).

    Parameters
    ----------
    config : Mapping
        The workflow's config (the scene's settings and presets are read from it).
    preset : str
        The preset whose scene plans the cases.
    ln_a : float, optional
        Natural log of the law's scale (ln of seconds); the default is fitted on the published
        cases (docs/replay/cost_law.json).
    b_particles : float, optional
        Exponent of the sphere count N (dimensionless).
    b_steps : float, optional
        Exponent of the estimated steps S (dimensionless).
    """

    config: Mapping
    preset: str
    ln_a: float = DEFAULT_LAW["ln_a"]
    b_particles: float = DEFAULT_LAW["b_particles"]
    b_steps: float = DEFAULT_LAW["b_steps"]

    @classmethod
    def from_config(cls, config: Mapping, preset: str | None = None) -> "PlannedCost":
        """The law of ``config["converge"]["cost_law"]`` (keys left out keep ``DEFAULT_LAW``).

        Parameters
        ----------
        config : Mapping
            The workflow's config.
        preset : str or None, optional
            The preset whose scene plans the cases; None: ``config["preset"]``.

        Returns
        -------
        PlannedCost
            The cost of cases of that preset under that law.
        """
        law = {**DEFAULT_LAW, **dict((config.get("converge") or {}).get("cost_law") or {})}
        return cls(config, preset or config["preset"], float(law["ln_a"]), float(law["b_particles"]),
                   float(law["b_steps"]))

    def of_work(self, work: np.ndarray) -> np.ndarray:
        """CPU seconds of cases of known planned work, by the law.

        Parameters
        ----------
        work : numpy.ndarray
            Shape (n, 2): the sphere count N and the estimated steps S of each case
            (``planned_work``).

        Returns
        -------
        numpy.ndarray
            CPU seconds, shape (n,).
        """
        work = np.asarray(work, float)
        return np.exp(self.ln_a + self.b_particles * np.log(work[:, 0]) + self.b_steps * np.log(work[:, 1]))

    def __call__(self, points) -> np.ndarray:
        return self.of_work(planned_work(points, self.config, self.preset))

    def calibrated(self, table: pd.DataFrame) -> "PlannedCost":
        """The same law with ``ln_a`` set so that its median ratio to the finished cases' measured
        ``cpu_time`` is 1 (this machine's speed); unchanged with none finished.

        Parameters
        ----------
        table : pandas.DataFrame
            A results table; its rows with status ok and a ``cpu_time`` (s) > 0 are used.

        Returns
        -------
        PlannedCost
            A new cost with the calibrated ``ln_a`` (the same exponents), or `self` when no row
            qualifies.
        """
        X, cpu = finished_costs(table)
        if not len(cpu):
            return self
        ratio = np.median(np.log(cpu) - np.log(self(X)))
        return PlannedCost(self.config, self.preset, self.ln_a + float(ratio), self.b_particles, self.b_steps)


def finished_costs(table: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """(X in NAMES order, CPU seconds) of the rows that finished (status ok) with a CPU time > 0."""
    cpu = pd.to_numeric(table.get("cpu_time", pd.Series(np.nan, index=table.index)), errors="coerce").to_numpy(float)
    ok = (table["status"].astype(str).str.strip() == "ok").to_numpy() & np.isfinite(cpu) & (cpu > 0)
    return table.loc[ok, list(NAMES)].to_numpy(float), cpu[ok]


def fit_law(tables: Iterable[pd.DataFrame], config: Mapping) -> dict:
    """Fit the law's exponents on finished cases of several tables (each table one machine and
    session, with an intercept of its own: the sessions' machines differed up to 2x in speed), and
    ``ln_a`` as the median of those intercepts. Cases whose preset the config does not know are
    left out. Returns the law and its fit: residual SD (within sessions), cases, per-table
    intercepts."""
    Ns, Ss, ys, groups = [], [], [], []
    for g, t in enumerate(tables):
        t = t[t["preset"].astype(str).isin(config["presets"])]
        for preset, part in t.groupby("preset"):
            X, cpu = finished_costs(part)
            if not len(cpu):
                continue
            w = planned_work(X, config, str(preset))
            Ns.append(w[:, 0])
            Ss.append(w[:, 1])
            ys.append(np.log(cpu))
            groups.append(np.full(len(cpu), g))
    if not ys:
        raise ValueError("no finished case with a CPU time and a known preset to fit the cost law on")
    N, S, y, grp = (np.concatenate(a) for a in (Ns, Ss, ys, groups))
    labels = np.unique(grp)
    D = np.column_stack([(grp == g).astype(float) for g in labels] + [np.log(N), np.log(S)])
    coef, *_ = np.linalg.lstsq(D, y, rcond=None)
    resid = y - D @ coef
    intercepts = coef[:len(labels)]
    return {"ln_a": float(np.median(intercepts)), "b_particles": float(coef[-2]), "b_steps": float(coef[-1]),
            "residual_sd": float(np.std(resid, ddof=D.shape[1])), "cases": int(len(y)),
            "table_intercepts": [float(c) for c in intercepts]}
