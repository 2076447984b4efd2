"""Is the map right?  The workflow's stopping criteria, stated against the noise.

The study's rule (``study_rule``) asks whether five statistics of the sample stopped moving.
With noisy cases it measures step size, not error: it stops on the budget, and its statistics
converge to noise-biased values.  A user's question is about the map, so the workflow stops when
these hold (each in config ``converge:``, each reported with the batch at which it held; only
those in ``stop_on`` block the stop, by default the map's own error alone):

0. ``map_error`` -- the map's own error against a tolerance per target that the user sets
   (``map_error.tolerance``, target units), estimated two independent ways, and the larger
   taken: (a) cross-validation net of the noise, sqrt(max(CV RMSE^2 - noise^2, 0)) on the LDS
   share (criterion 1's numbers), the error measured at cases the model has not seen; (b) the
   model's posterior: the RMS posterior SD of the map over each map grid (the design box, the
   machine plane, the powder plane), the worst grid. (a) checks that the model is not more sure
   than its held-out errors allow; (b) reads the error where the maps are read and does not
   scatter with the noise of a few held-out cases. Both are in target units, so a cheap, noisy
   preset is judged by the same standard as a precise one: its noise is subtracted in (a) and
   carried by the GP in (b). The larger of the two, times ``margin``, is held against the
   tolerance: an estimate that is right on average crosses the tolerance first where it happens
   to read low, so a stop on the bare estimate is within tolerance only about half the time; the
   margin, calibrated on a replay against a known truth (``replay``, docs/replay), makes the stop
   an upper bound.
1. ``cv_rmse`` -- the model's K-fold cross-validated RMSE against the cases at or below
   ``factor`` x the noise SD.  *Why*: it is the error of the map at points the model has not
   seen, measured, not assumed.  Against noisy observations it can never fall below the noise
   SD (E[(y - m)^2] = noise^2 + map error^2), so the target is set against the noise: factor
   1.2 means a map error of at most sqrt(1.2^2 - 1) = 0.66 noise SD.  The model, its
   hyperparameters included, is refitted inside every fold on every case outside it.  With
   active batches only the LDS share's predictions are scored: the active cases sit where the
   model was unsure and, per CPU-second, where cases are cheap (the thin gaps at large d, where
   the error is largest), so scored on every case the RMSE weighs those regions by how often
   they were chosen, not by their share of the map (on a known truth with half the cases
   crowded into a sharp corner: 1.5-1.8x the map's error; in the study's loop at 240 cases the
   two scorings happened to agree within 2 %); the LDS share is a uniform sample of the design
   space, so scored on it the RMSE estimates the map's average error.  Noise SD: the RMS of the
   scored cases' per-case ``{target}_sd`` when present, else the model's fitted noise.
2. ``map_change`` -- the RMS (default; or the largest) change of the map's mean between the
   previous batch and this one, over the map grids (a grid over the design box, the machine
   map's h x v grid, the powder maps' d x f grid of config ``maps:``), below ``fraction`` x the
   noise SD (default 0.2).  RMS by default because the largest change sits at the corners of
   the box, where a GP extrapolates and moves most (measured: max ~4x the RMS at 80-96 cases);
   the largest change of each grid is reported beside it.
   *Why*: CV error is an average over the cases; a map that still moves where the user reads
   it (the machine and powder planes) is not settled even when the average error is fine.
   Stated against the noise because a change smaller than a fraction of one case's noise is
   below what any single case could show.
3. ``ci`` -- bootstrap confidence intervals (percentile, ``scipy.stats.bootstrap``) of the
   partition statistics (mean, SD, median, skewness, excess kurtosis of each target) narrower
   than a tolerance per statistic: half-width / max(|value|, floor) with the study's floors
   (1 for skewness and kurtosis).  *Why*: the study reports these statistics; this says how
   well the sample pins them down (their error), where the study's rule says only how much
   they moved (their step).  On an LDS sample the case-resampling bootstrap is conservative
   for the design-space part of the spread (QMC errors fall faster than i.i.d. ones) and right
   for the noise part; it measures precision, not the noise bias of the SD and kurtosis.

``evaluate`` computes all three at one batch, ``Tracker`` keeps the path (the first batch at
which each held, and whether all the required ones hold now).
"""
from __future__ import annotations

import copy
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd
from scipy import stats
from sklearn.model_selection import KFold

from .. import slices
from ..design import TARGETS, Design
from ..schema import checked
from ..study_rule.rule import DEFAULT_FLOORS, STATISTICS
from ..table import usable_cases
from .model import FitFunction, MapModel, table_data

CRITERIA: tuple[str, ...] = ("map_error", "cv_rmse", "map_change", "ci")
MIN_CASES = 5  # usable cases a target needs before its model is fitted and the criteria evaluated


def settings(cfg: Mapping | None, targets: Sequence[str] | None = None) -> dict[str, Any]:
    """The criteria's settings from config ``converge:`` (or a part of it), the schema's defaults
    filled (``spreadmap.schema.checked``): ``criteria(checked("converge", cfg), targets)``.

    Parameters
    ----------
    cfg : Mapping or None
        The config's ``converge:`` section, whole or in part; None or {}: the defaults.
    targets : sequence of str or None, optional
        The loop's targets: a map-error tolerance for any other target is refused. None: not checked.

    Returns
    -------
    dict
        As ``criteria``.

    Raises
    ------
    ValueError
        If the section does not match the schema, or a tolerance names a target not in `targets`;
        the message names the key.
    """
    return criteria(checked("converge", cfg), targets)


def criteria(conv: Mapping, targets: Sequence[str] | None = None) -> dict[str, Any]:
    """The criteria's settings picked from a ``converge:`` section whose defaults are filled
    (``spreadmap.schema.checked``, done once by the caller: ``stepper.step_settings``).

    The one reader of the criteria's keys (``stop_on``, ``hold_for``, ``min_stop_cases``, ``map_error``, ``cv_rmse``,
    ``map_change``, ``ci``); their defaults are the schema's alone, and the schema refuses unknown
    criteria, statistics and keys. A CI half-width of null drops that statistic from the criterion.

    Parameters
    ----------
    conv : Mapping
        The ``converge:`` section as ``checked("converge", ...)`` returns it.
    targets : sequence of str or None, optional
        The loop's targets: a map-error tolerance for any other target is refused. None: not checked.

    Returns
    -------
    dict
        ``stop_on``, ``hold_for``, ``min_stop_cases`` and one dict per criterion (copies).

    Raises
    ------
    ValueError
        If a tolerance names a target not in `targets`; the message names the key.
    """
    out = copy.deepcopy({key: conv[key] for key in ("stop_on", "hold_for", "min_stop_cases", *CRITERIA)})
    out["ci"]["halfwidth"] = {k: v for k, v in out["ci"]["halfwidth"].items() if v is not None}
    unknown = sorted(set(out["map_error"]["tolerance"]) - set(targets)) if targets is not None else []
    if unknown:
        raise ValueError(f"config key 'converge.map_error.tolerance': targets {unknown} are not the loop's "
                         f"targets; allowed: {list(targets)}")
    return out


# ----------------------------------------------------------------------------------------------
# the map grids
# ----------------------------------------------------------------------------------------------
def map_grids(maps_cfg: Mapping | None = None, ranges: Design | Mapping | None = None, box_k: int = 5,
              n_d: int | None = None, n_f: int | None = None) -> dict[str, np.ndarray]:
    """Points (physical units, NAMES order) where the maps are read: the maps' slices
    (``spreadmap.slices``) as config ``maps:`` sets them, and the design box.

    * ``box``: box_k^N cell centres of the design box (no face is over-weighted; ``slices.box``);
    * ``machine``: the machine map's n_h x n_v grid of h and v at its f and d (``slices.MACHINE``);
    * ``powder``: the powder maps' n_d x n_f grid of d and f at their h and v (``slices.POWDER``;
      n_d, n_f: None, the slice's 41 and 5).
    Fixed values and sizes from config ``maps:``, the schema's defaults filled.
    """
    config = {"maps": maps_cfg or {}}
    return {"box": slices.box(ranges, box_k),
            "machine": slices.MACHINE.points(config, Design.of(ranges)),
            "powder": slices.POWDER.points(config, Design.of(ranges), {"d_um": n_d, "f": n_f})}


# ----------------------------------------------------------------------------------------------
# (1) cross-validated RMSE against the noise
# ----------------------------------------------------------------------------------------------
def cv_rmse(X, y, noise_sd, fit: FitFunction, folds: int = 5, seed: int = 0,
            scored=None) -> dict[str, float]:
    """K-fold CV (shuffled, seeded) of ``fit``: the model is refitted inside every fold, on every
    case outside it.

    ``scored`` (booleans, one per case; default all): the cases whose held-out predictions are
    scored. Returns ``rmse`` (their held-out predictions against their observations),
    ``heldout_noise_sd`` (their RMS per-case noise SD, NaN when not given), ``n_scored`` and
    ``rmse_all_cases`` (scored on every case).
    """
    X = np.asarray(X, float)
    y = np.asarray(y, float)
    folds = int(min(folds, len(y)))
    if folds < 2:
        raise ValueError(f"cross-validation needs at least 2 cases, got {len(y)}")
    scored = np.ones(len(y), bool) if scored is None else np.asarray(scored, bool)
    if scored.shape != y.shape or not scored.any():
        raise ValueError(f"scored must mark at least one of the {len(y)} cases, got {scored.sum()} of {scored.size}")
    pred = np.empty_like(y)
    for train, test in KFold(folds, shuffle=True, random_state=seed).split(X):
        sd = None if noise_sd is None else np.asarray(noise_sd, float)[train]
        pred[test] = fit(X[train], y[train], sd).predict(X[test])
    rmse = float(np.sqrt(np.mean((pred - y)[scored] ** 2)))
    held = (float(np.sqrt(np.mean(np.asarray(noise_sd, float)[scored] ** 2))) if noise_sd is not None
            else float("nan"))
    return {"rmse": rmse, "heldout_noise_sd": held, "n_scored": int(scored.sum()),
            "rmse_all_cases": float(np.sqrt(np.mean((pred - y) ** 2)))}


# ----------------------------------------------------------------------------------------------
# (2) the maps' change between batches
# ----------------------------------------------------------------------------------------------
def map_change(prev: MapModel, curr: MapModel, grids: Mapping[str, np.ndarray]) -> dict[str, float]:
    """Max and RMS of |mean_curr - mean_prev| over all grid points, and the max per grid."""
    out: dict[str, float] = {}
    diffs = []
    for name, pts in grids.items():
        d = np.abs(np.asarray(curr.predict(pts), float) - np.asarray(prev.predict(pts), float))
        out[f"max_{name}"] = float(np.max(d))
        diffs.append(d)
    alld = np.concatenate(diffs)
    out["max"] = float(np.max(alld))
    out["rms"] = float(np.sqrt(np.mean(alld**2)))
    return out


# ----------------------------------------------------------------------------------------------
# (3) bootstrap confidence intervals of the partition statistics
# ----------------------------------------------------------------------------------------------
def _stat_functions():
    return {
        "mean": lambda x, axis=-1: np.mean(x, axis=axis),
        "std": lambda x, axis=-1: np.std(x, ddof=1, axis=axis),
        "median": lambda x, axis=-1: np.median(x, axis=axis),
        "skewness": lambda x, axis=-1: stats.skew(x, bias=True, axis=axis),
        "kurtosis": lambda x, axis=-1: stats.kurtosis(x, fisher=True, bias=True, axis=axis),
    }


def bootstrap_ci(values, level: float = 0.9, resamples: int = 1000, seed: int = 0,
                 statistics: Sequence[str] = STATISTICS) -> dict[str, dict[str, float]]:
    """Percentile bootstrap CI of each statistic (the study's estimators), seeded.

    Returns ``{statistic: {"value", "low", "high", "halfwidth"}}``; NaN for fewer than 3 values.
    """
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    funcs = _stat_functions()
    out = {}
    for i, s in enumerate(statistics):
        if x.size < 3 or np.ptp(x) == 0:
            out[s] = {"value": float("nan"), "low": float("nan"), "high": float("nan"),
                      "halfwidth": float("nan")}
            continue
        res = stats.bootstrap((x,), funcs[s], n_resamples=int(resamples), confidence_level=level,
                              method="percentile", vectorized=True,
                              rng=np.random.default_rng([int(seed), i]))
        lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
        out[s] = {"value": float(funcs[s](x)), "low": lo, "high": hi, "halfwidth": (hi - lo) / 2}
    return out


def ci_widths(values, halfwidth: Mapping[str, float], level: float = 0.9, resamples: int = 1000,
              seed: int = 0, floors: Mapping[str, float] | None = None) -> dict[str, dict[str, float]]:
    """Bootstrap CIs with each half-width relative to max(|value|, floor) and its tolerance."""
    fl = {**DEFAULT_FLOORS, **(floors or {})}
    cis = bootstrap_ci(values, level, resamples, seed, statistics=tuple(halfwidth))
    for s, c in cis.items():
        c["relative_halfwidth"] = c["halfwidth"] / max(abs(c["value"]), fl[s]) if np.isfinite(c["value"]) else float("nan")
        c["tolerance"] = float(halfwidth[s])
        c["ratio"] = c["relative_halfwidth"] / c["tolerance"]
    return cis


# ----------------------------------------------------------------------------------------------
# (0) the map's own error, two ways, and the statistics of the map over the box
# ----------------------------------------------------------------------------------------------
def posterior_error(model: MapModel, grids: Mapping[str, np.ndarray]) -> dict[str, float]:
    """RMS posterior SD of the map over each grid (target units) and the worst grid's."""
    out = {name: float(np.sqrt(np.mean(np.asarray(model.predict(pts, return_std=True)[1], float) ** 2)))
           for name, pts in grids.items()}
    out["worst"] = max(out.values())
    return out


def map_statistics(model: MapModel, box: np.ndarray, draws: int = 64, seed: int = 0,
                   level: float = 0.9) -> dict[str, dict[str, float]]:
    """The study's five statistics of the *map* over the design box (uniform on ``box``, the box
    grid's cell centres), from joint posterior draws of the model: per statistic the value of the
    mean map and a ``level`` interval over the draws. These are statistics of the noise-free
    response; the raw cases' SD and kurtosis carry the noise on top."""
    if not hasattr(model, "draws"):
        return {}
    rng = np.random.default_rng([int(seed), 23])
    D = np.asarray(model.draws(box, int(draws), rng), float)
    mean_map = np.asarray(model.predict(box), float)
    funcs = _stat_functions()
    q = (1 - level) / 2
    out = {}
    for name in STATISTICS:
        per_draw = funcs[name](D, axis=1)
        out[name] = {"value": float(funcs[name](mean_map)), "low": float(np.quantile(per_draw, q)),
                     "high": float(np.quantile(per_draw, 1 - q))}
    return out


# ----------------------------------------------------------------------------------------------
# all three at one batch
# ----------------------------------------------------------------------------------------------
def evaluate(table: pd.DataFrame, fit: FitFunction, targets: Sequence[str] = TARGETS,
             prev_table: pd.DataFrame | None = None, grids: Mapping[str, np.ndarray] | None = None,
             crit: Mapping | None = None, seed: int = 0,
             floors: Mapping[str, float] | None = None,
             stats_table: pd.DataFrame | None = None) -> dict[str, Any]:
    """The three criteria on the cases of ``table`` (and the previous batch's ``prev_table``).

    Each criterion gets ``value`` (the worst target's ratio to its threshold: <= 1 holds),
    ``holds``, and per target the numbers behind it.  ``map_change`` is None without a
    previous table.  ``models`` holds the fitted models (not JSON; dropped by ``to_json``).
    ``stats_table``: the cases whose statistics the CIs are about and whose cross-validated
    predictions the CV RMSE scores (default ``table``; with active batches, the LDS cases only:
    the others are not a uniform sample of the design space). Its rows must be rows of ``table``
    (the same index). ``crit``: the criteria's settings (``settings`` or ``criteria``; None: the
    schema's defaults).
    """
    s = crit if crit is not None else settings(None)
    if stats_table is not None and not (table.index.is_unique and stats_table.index.isin(table.index).all()):
        raise ValueError("stats_table must be rows of table (a subset of its unique index)")
    grids = grids if grids is not None else map_grids(box_k=int(s["map_change"]["box_k"]))
    out: dict[str, Any] = {"n_cases": int(len(table)), "models": {}}
    per: dict[str, dict] = {c: {} for c in CRITERIA}
    for t in targets:
        X, y, sd = table_data(table, t)
        if len(y) < MIN_CASES:  # too few usable cases to fit and cross-validate: no criterion holds yet
            out.setdefault("too_few_cases", {})[t] = int(len(y))
            continue
        model = fit(X, y, sd)
        out["models"][t] = model
        noise = float(np.sqrt(np.mean(sd**2))) if sd is not None else float(model.noise_sd)
        source = "per-case noise of the table" if sd is not None else "the model's fitted noise"
        scored = None if stats_table is None else usable_cases(table, [t]).index.isin(usable_cases(stats_table, [t]).index)
        c = cv_rmse(X, y, sd, fit, folds=int(s["cv_rmse"]["folds"]), seed=seed,
                    scored=None if scored is None or not scored.any() else scored)
        cv_noise = c["heldout_noise_sd"] if sd is not None else noise  # the scored cases' noise
        thr = float(s["cv_rmse"]["factor"]) * cv_noise
        per["cv_rmse"][t] = {"rmse": c["rmse"], "noise_sd": cv_noise, "noise_source": source,
                             "threshold": thr, "ratio": c["rmse"] / thr,
                             "map_error_estimate": float(np.sqrt(max(c["rmse"] ** 2 - cv_noise**2, 0.0))),
                             "scored": "all cases" if c["n_scored"] == len(y) else "the LDS share",
                             "n_scored": c["n_scored"], "rmse_all_cases": c["rmse_all_cases"]}
        if prev_table is not None and len(table_data(prev_table, t)[1]) >= MIN_CASES:
            Xp, yp, sdp = table_data(prev_table, t)
            ch = map_change(fit(Xp, yp, sdp), model, grids)
            thr = float(s["map_change"]["fraction"]) * noise
            stat = s["map_change"]["statistic"]
            per["map_change"][t] = {**ch, "noise_sd": noise, "threshold": thr, "statistic": stat,
                                    "ratio": ch[stat] / thr}
        post = posterior_error(model, grids)
        tol = float(s["map_error"]["tolerance"].get(t, float("nan")))
        raw = max(per["cv_rmse"][t]["map_error_estimate"], post["worst"])
        estimate = float(s["map_error"]["margin"]) * raw
        per["map_error"][t] = {"tolerance": tol, "cv_net_of_noise": per["cv_rmse"][t]["map_error_estimate"],
                               "posterior_rms_sd": post, "raw_estimate": raw,
                               "margin": float(s["map_error"]["margin"]), "estimate": estimate,
                               "ratio": estimate / tol if np.isfinite(tol) else float("nan")}
        if int(s["map_error"].get("draws") or 0) > 0:
            out.setdefault("map_statistics", {})[t] = map_statistics(model, grids["box"],
                                                                     int(s["map_error"]["draws"]), seed)
        y_stats = y if stats_table is None else table_data(stats_table, t)[1]
        cis = ci_widths(y_stats, s["ci"]["halfwidth"], level=float(s["ci"]["level"]),
                        resamples=int(s["ci"]["resamples"]), seed=seed, floors=floors)
        per["ci"][t] = {k: {kk: float(vv) for kk, vv in v.items()} for k, v in cis.items()}
        per["ci"][t]["ratio"] = float(max(v["ratio"] for v in cis.values()))
    for c in CRITERIA:
        if c == "map_error":  # only the targets given a tolerance
            per[c] = {t: v for t, v in per[c].items() if np.isfinite(v["ratio"])}
        if not per[c]:
            out[c] = None
            continue
        ratio = max(v["ratio"] for v in per[c].values())
        out[c] = {"value": float(ratio), "holds": bool(ratio <= 1.0), "targets": per[c]}
    return out


def to_json(result: Mapping[str, Any]) -> dict[str, Any]:
    """``evaluate``'s result without the fitted models."""
    return {k: v for k, v in result.items() if k != "models"}


class Tracker:
    """The path of a run: for every batch the criteria, the first batch at which each held, and
    the stop decision (all criteria of ``stop_on`` hold at ``hold_for`` consecutive batches, the
    last with at least ``min_cases`` cases)."""

    def __init__(self, stop_on: Sequence[str] = CRITERIA, hold_for: int = 1,
                 history: Sequence[Mapping] | None = None, min_cases: int = 0):
        bad = set(stop_on) - set(CRITERIA)
        if bad:
            raise ValueError(f"unknown criteria {sorted(bad)}; allowed: {list(CRITERIA)}")
        self.stop_on = list(stop_on)
        self.hold_for = max(int(hold_for), 1)
        self.min_cases = int(min_cases)
        self.history: list[dict] = [dict(h) for h in (history or [])]

    def add(self, n_cases: int, result: Mapping[str, Any]) -> dict:
        entry = {"n": int(n_cases)}
        for c in CRITERIA:
            r = result.get(c)
            entry[c] = None if r is None else {"value": r["value"], "holds": r["holds"]}
        entry["all_hold"] = all(entry[c] is not None and entry[c]["holds"] for c in self.stop_on)
        self.history.append(entry)
        return entry

    def first_held(self) -> dict[str, int | None]:
        """The first batch (number of cases) at which each criterion held."""
        out = {}
        for c in CRITERIA:
            out[c] = next((h["n"] for h in self.history if h.get(c) and h[c]["holds"]), None)
        return out

    def stop(self) -> bool:
        tail = self.history[-self.hold_for:]
        return (len(tail) == self.hold_for and all(h["all_hold"] for h in tail)
                and tail[-1]["n"] >= self.min_cases)

    def summary(self) -> dict[str, Any]:
        last = self.history[-1] if self.history else {}
        return {"stop_on": self.stop_on, "hold_for": self.hold_for, "min_stop_cases": self.min_cases,
                "first_held": self.first_held(),
                "now": {c: last.get(c) for c in CRITERIA}, "criteria_met": self.stop(),
                "path": self.history}
