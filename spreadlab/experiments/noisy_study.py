"""The sampling-design study with noise: cases needed for a map of known accuracy.  (No DEM.)

``sampling_study`` counts the cases the study's rule needs on noise-free functions; with noisy
cases that rule stops on the budget.  This study asks the user's question instead: how many
cases does each design need before the *map* is right, i.e. before the RMSE of the fitted
model's mean against the known truth, over the map grids, falls to a target.

* Truth: an MFR-like function, the project's ``flow_curve`` standardised and scaled to the main
  job's mean 0.29 and SD 0.085 (``mfr_like``).
* Noise (``NOISE_MODELS``): multiplicative 3 % and 7 % (y (1 + r e), e ~ N(0, 1)), and
  ``counting``: the per-case counting noise the scene reports, relative SD 0.45 / sqrt(N) with
  N the spheres passing the gap in the default preset's window, N = 76 y h / d (5 d wide, 8 d
  long window: N = y x (h/d) x 40 d^2 / (pi d^2 / 6)); there the fit is given each case's noise
  SD (computed from the observed value, as a real case would report it).
* Designs: ``lds`` (scrambled Halton prefix, seeded), ``random`` (i.i.d. uniform, seeded),
  ``lattice`` (k^4 points, ends included; only its noise varies with the seed), ``active``
  (LDS start, then batches by ``active.choose_batch``, integrated variance reduction over the
  map grids, candidates seeded), ``active_per_cpu`` (the same per planned CPU-second: the law
  ``case_cost`` itself, as the loop uses the scene's planned cost).
* CPU: each case costs ``case_cost`` (the default scene's law, below) times a log-normal
  scatter of SD 0.19; every checkpoint records the CPU spent so far (``cpu_cases``), so the
  designs are compared at equal CPU as well as at equal cases (``cost_study``).
* Model: the map's model, ``model.make_map_fit`` (the same for every design), refitted from
  scratch at every checkpoint. (docs/sampling's published numbers were measured with an earlier
  stand-in GP on unit inputs and a cost fitted on observed CPU; the loop's replay, docs/replay,
  is the current study of the loop.)
* Map RMSE: over the map grids of ``map_criteria.map_grids`` (box cell centres, machine plane,
  powder plane), also reported on the box alone.  ``n_needed``: the first checkpoint at which
  the map RMSE is at or below the target; censored (NaN) when not reached within the budget.

The full study is run once (``benchmarks/noisy_study.py --out docs/sampling``);
tests and the workflow run a small version.
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np
import pandas as pd

from spreadlab.experiments.sampling_study import flow_curve
from spreadmap.design import NAMES, to_physical, to_unit
from spreadmap.files import write_text_atomically
from spreadmap.loop import active
from spreadmap.loop.map_criteria import map_grids
from spreadmap.loop.model import make_map_fit
from spreadmap.sampling import halton_unit, lattice_unit

MEAN, SD = 0.29, 0.085
# ln CPU seconds of a default-preset case on this scene: least squares on 60 finished cases
# (docs/study/cases_lds.csv's 16, docs/precision's shipped arm's 32, docs/fidelity's default 12),
# in 1, f, ln d, ln(h/d), ln v, ln(h/d)^2; residual SD 0.19; clipped to the measured 25-1350 s
COST_LAW = (12.099, -1.159, -1.415, -2.403, -0.893, 1.402)
COST_SCATTER = 0.19
COST_RANGE_S = (25.0, 1350.0)


def _flow_moments() -> tuple[float, float]:
    raw = flow_curve(halton_unit(2**15, 2024))
    return float(raw.mean()), float(raw.std())


_FLOW = _flow_moments()


def mfr_like(u: np.ndarray) -> np.ndarray:
    """flow_curve standardised (moments from 2^15 Halton points) and scaled to mean 0.29, SD 0.085."""
    return MEAN + SD * (flow_curve(u) - _FLOW[0]) / _FLOW[1]


def case_cost(u: np.ndarray, ranges: dict | None = None) -> np.ndarray:
    """CPU seconds of cases at unit-cube points u by the scene's law (COST_LAW)."""
    p = to_physical(np.atleast_2d(u), ranges)
    f, d, h, v = p.T
    r = np.log(h / d)
    c = COST_LAW
    ln_cpu = c[0] + c[1] * f + c[2] * np.log(d) + c[3] * r + c[4] * np.log(v) + c[5] * r * r
    return np.clip(np.exp(ln_cpu), *COST_RANGE_S)


def counting_sd(y: np.ndarray, u: np.ndarray, ranges: dict | None = None) -> np.ndarray:
    """Counting noise SD of a case: y x 0.45 / sqrt(N), N = max(76 y h/d, 1) spheres passing."""
    p = to_physical(u, ranges)
    n = np.maximum(76.0 * np.maximum(y, 0.0) * p[:, 2] / p[:, 1], 1.0)
    return np.abs(y) * 0.45 / np.sqrt(n)


NOISE_MODELS: dict[str, str] = {
    "mult3": "multiplicative, 3 %",
    "mult7": "multiplicative, 7 %",
    "counting": "counting, 0.45 / sqrt(N) (per-case SD given to the fit)",
}


def observe(u: np.ndarray, noise: str, rng: np.random.Generator,
            truth: Callable = mfr_like) -> tuple[np.ndarray, np.ndarray | None]:
    """Noisy observations at u and the per-case noise SD the fit is told (None: unknown)."""
    y = truth(u)
    e = rng.standard_normal(len(y))
    if noise == "mult3":
        return y * (1 + 0.03 * e), None
    if noise == "mult7":
        return y * (1 + 0.07 * e), None
    if noise == "counting":
        obs = y + counting_sd(y, u) * e
        return obs, counting_sd(obs, u)
    raise ValueError(f"noise model {noise!r}; allowed: {list(NOISE_MODELS)}")


def _rmse(model, truth, grids_u: Mapping[str, np.ndarray]) -> tuple[float, float]:
    errs = {k: model.predict(to_physical(g)) - truth(g) for k, g in grids_u.items()}
    allv = np.concatenate(list(errs.values()))
    return float(np.sqrt(np.mean(allv**2))), float(np.sqrt(np.mean(errs["box"] ** 2)))


def one_run(method: str, noise: str, seed: int, checkpoints: Sequence[int], start: int = 32,
            batch: int = 16, truth: Callable = mfr_like, n_candidates: int = 2048,
            acquisition: str = "ivr") -> list[dict]:
    """Map RMSE at each checkpoint of one design, noise model and seed."""
    grids_u = {k: to_unit(v) for k, v in map_grids().items()}
    reference = np.vstack([to_physical(g) for g in grids_u.values()])
    rng = np.random.default_rng([int(seed), 7])
    cost_rng = np.random.default_rng([int(seed), 11])

    def spent(u_new):  # observed CPU of new cases: the law with its scatter (its own random stream)
        return case_cost(u_new) * np.exp(COST_SCATTER * cost_rng.standard_normal(len(u_new)))

    fit = make_map_fit({"seed": int(seed)})
    n_max = max(checkpoints)
    rows = []
    if method in ("lds", "random", "lattice"):
        if method == "lds":
            u_all = halton_unit(n_max, seed)
        elif method == "random":
            u_all = np.random.default_rng([int(seed), 3]).random((n_max, len(NAMES)))
        y_all = sd_all = None
        cpu_all = None if method == "lattice" else np.cumsum(spent(u_all))
        for n in checkpoints:
            u = lattice_unit(round(n ** 0.25)) if method == "lattice" else u_all[:n]
            if method == "lattice":
                y, sd = observe(u, noise, np.random.default_rng([int(seed), 7, n]), truth)
            else:
                if y_all is None:
                    y_all, sd_all = observe(u_all, noise, rng, truth)
                y, sd = y_all[:n], None if sd_all is None else sd_all[:n]
            t = time.process_time()
            m = fit(to_physical(u), y, sd)
            rmse = _rmse(m, truth, grids_u)
            cpu_cases = float(spent(u).sum()) if method == "lattice" else float(cpu_all[n - 1])
            rows.append({"n": n, "map_rmse": rmse[0], "box_rmse": rmse[1],
                         "cpu_s": time.process_time() - t, "cpu_cases": cpu_cases})
        return rows
    if method not in ("active", "active_per_cpu"):
        raise ValueError(f"method {method!r}; allowed: lds, random, lattice, active, active_per_cpu")
    if method == "active_per_cpu":
        acquisition = "ivr_per_cpu"
    u = halton_unit(start, seed)
    y, sd = observe(u, noise, rng, truth)
    cpu = spent(u)
    while True:
        t = time.process_time()
        m = fit(to_physical(u), y, sd)
        n = len(u)
        if n in checkpoints:
            rmse = _rmse(m, truth, grids_u)
            rows.append({"n": n, "map_rmse": rmse[0], "box_rmse": rmse[1], "cpu_cases": float(cpu.sum())})
        if n >= n_max:
            rows[-1]["cpu_s"] = time.process_time() - t
            break
        step = min(batch, n_max - n)
        cost = None
        if acquisition == "ivr_per_cpu":
            def cost(P):  # the plan's cost: the law itself, as the loop's planned cost (cost.PlannedCost)
                return case_cost(to_unit(np.asarray(P, float)))
        new = active.choose_batch([m], step, seed=seed * 1000 + n, n_candidates=n_candidates,
                                  acquisition=acquisition, reference=reference, cost=cost)
        if rows and rows[-1]["n"] == n:
            rows[-1]["cpu_s"] = time.process_time() - t  # fit and batch choice
        u_new = to_unit(new)
        y_new, sd_new = observe(u_new, noise, rng, truth)
        u = np.vstack([u, u_new])
        cpu = np.concatenate([cpu, spent(u_new)])
        y = np.concatenate([y, y_new])
        sd = None if sd is None else np.concatenate([sd, sd_new])
    return rows


def run(methods: Sequence[str] = ("lds", "random", "lattice", "active"),
        noises: Sequence[str] = tuple(NOISE_MODELS), seeds: Sequence[int] = range(8),
        n_max: int = 256, start: int = 32, batch: int = 16,
        checkpoints: Sequence[int] | None = None, truth: Callable = mfr_like,
        n_candidates: int = 2048, log: Callable[[str], None] | None = None,
        partial: str | Path | None = None) -> pd.DataFrame:
    """The tidy table: method, noise, seed, n, map_rmse, box_rmse, cpu_s (one row per checkpoint).

    Every run of a design, noise model and seed refits the map's model from scratch at each
    checkpoint and measures its RMSE against the truth over the map grids (see the module
    docstring); seeds are the outer loop, so a run cut short has every design and noise at equal
    seeds.

    Parameters
    ----------
    methods : sequence of str, optional
        The designs: "lds", "random", "lattice", "active", "active_per_cpu".
    noises : sequence of str, optional
        The noise models (keys of ``NOISE_MODELS``).
    seeds : sequence of int, optional
        The seeds.
    n_max : int, optional
        Cases per run at most (the budget).
    start : int, optional
        Cases in the active designs' LDS start.
    batch : int, optional
        Cases per batch of the active designs.
    checkpoints : sequence of int or None, optional
        The numbers of cases at which the map is scored; None: every batch (start, start + batch,
        ..., n_max). The lattice is scored at its sizes k^4 <= n_max instead.
    truth : callable, optional
        The truth on the unit cube, u[n, 4] -> y[n]; default ``mfr_like``.
    n_candidates : int, optional
        Candidate points per batch of the active designs.
    log : callable or None, optional
        Called with one line after each run (its CPU seconds); None: silent.
    partial : pathlib.Path or str or None, optional
        A CSV rewritten after every seed (the rows so far); None: none.

    Returns
    -------
    pandas.DataFrame
        One row per checkpoint: ``method``, ``noise``, ``seed``, ``n``, ``map_rmse`` (over all the
        map grids) and ``box_rmse`` (over the box alone), in MFR units; ``cpu_s`` (the process CPU
        time [s] at that checkpoint: the fit, its RMSE and, for the active designs, the batch
        choice) and ``cpu_cases`` (the cases' CPU so far by the cost law with its scatter [s]).

    Raises
    ------
    ValueError
        If a method or a noise model is unknown.
    """
    if checkpoints is None:  # every batch
        checkpoints = [n for n in range(start, n_max + 1, batch)]
    lattice_n = [k**len(NAMES) for k in range(2, 12) if k**len(NAMES) <= n_max]
    rows = []
    for seed in seeds:  # seeds outermost: a run cut short has every design and noise at equal seeds
        for noise in noises:
            for method in methods:
                t = time.process_time()
                cps = lattice_n if method == "lattice" else list(checkpoints)
                for r in one_run(method, noise, int(seed), cps, start, batch, truth, n_candidates):
                    rows.append({"method": method, "noise": noise, "seed": int(seed), **r})
                if log:
                    log(f"{noise} seed {seed} {method}: {time.process_time() - t:.1f} CPU s")
        if partial is not None:
            write_text_atomically(partial, pd.DataFrame(rows).to_csv(index=False))  # a checkpoint, whole or not at all
    return pd.DataFrame(rows)


def cases_needed(table: pd.DataFrame, target: float) -> pd.DataFrame:
    """Per method, noise and seed: the first n with map RMSE <= target (NaN: not reached).

    Parameters
    ----------
    table : pandas.DataFrame
        ``run``'s table.
    target : float
        The map-RMSE target (MFR units, dimensionless).

    Returns
    -------
    pandas.DataFrame
        One row per (method, noise, seed): ``method``, ``noise``, ``seed``, ``target``,
        ``n_needed`` (float; NaN: not reached) and ``budget`` (the run's largest n).
    """
    rows = []
    for (m, z, s), g in table.groupby(["method", "noise", "seed"], sort=False):
        g = g.sort_values("n")
        hit = g.loc[g["map_rmse"] <= target, "n"]
        rows.append({"method": m, "noise": z, "seed": s, "target": target,
                     "n_needed": float(hit.iloc[0]) if len(hit) else np.nan, "budget": int(g["n"].max())})
    return pd.DataFrame(rows)


def summarise(needed: pd.DataFrame) -> pd.DataFrame:
    """Median, quartiles, min and max of n_needed over seeds, per method, noise and target.

    Not-reached runs count as above the budget (a quantile among them is NaN, ``not_reached`` says
    how many). Quantiles are ``numpy.quantile(method="lower")``: always an observed n.

    Parameters
    ----------
    needed : pandas.DataFrame
        ``cases_needed``'s tables (one or several targets).

    Returns
    -------
    pandas.DataFrame
        One row per (method, noise, target): ``runs``, ``not_reached``, ``min``, ``q25``,
        ``median``, ``q75``, ``max`` (cases) and ``budget``.
    """
    rows = []
    for (m, z, tgt), g in needed.groupby(["method", "noise", "target"], sort=False):
        v = np.where(np.isnan(g["n_needed"].to_numpy(float)), np.inf, g["n_needed"].to_numpy(float))
        q = np.quantile(v, [0.0, 0.25, 0.5, 0.75, 1.0], method="lower")
        q = [float(x) if np.isfinite(x) else np.nan for x in q]
        rows.append({"method": m, "noise": z, "target": tgt, "runs": int(v.size),
                     "not_reached": int(np.isinf(v).sum()), "min": q[0], "q25": q[1], "median": q[2],
                     "q75": q[3], "max": q[4], "budget": int(g["budget"].max())})
    return pd.DataFrame(rows)


def rmse_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Median and quartiles of the map RMSE over seeds at each n, per method and noise.

    Parameters
    ----------
    table : pandas.DataFrame
        ``run``'s table.

    Returns
    -------
    pandas.DataFrame
        One row per (method, noise, n): ``median``, ``q25``, ``q75`` of ``map_rmse`` (MFR units)
        and ``runs``.
    """
    g = table.groupby(["method", "noise", "n"])["map_rmse"]
    return pd.DataFrame({"median": g.median(), "q25": g.quantile(0.25), "q75": g.quantile(0.75),
                         "runs": g.size()}).reset_index()
