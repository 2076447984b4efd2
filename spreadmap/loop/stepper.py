"""One step of ``snakemake converge``: given the finished cases, stop or choose the next batch.

The run starts with ``converge.start`` LDS cases; after each batch ``step`` evaluates the map
criteria (``map_criteria``), keeps the path (the criteria at every batch, the first batch at
which each held), reports the study's rule beside them (``study_rule.batches_until_converged``
on the cases in run order, same batches), and decides:

* ``criteria met``: every criterion of ``converge.stop_on`` holds (``hold_for`` batches in a row),
  with at least ``converge.min_stop_cases`` cases run;
* ``case budget``: ``converge.budget`` cases run;
* ``CPU budget``: the cases' modelled CPU (``cost.PlannedCost``: the law of the spheres and
  steps each case's scene planned, the same on every machine, so that the same config stops at
  the same batch anywhere) reached ``converge.cpu_budget_h``; the measured CPU (``cpu_time``,
  else ``wall_time``) is reported beside it (without a cost law, the measured CPU decides);
* otherwise the next batch: ``converge.batch`` points (fewer if the budget is closer): with
  ``sampling: active`` a share ``lds_share`` of them are the next points of the LDS sequence and
  the rest are chosen by ``active.choose_batch`` (conditioned on that LDS share; with
  ``acquisition: ivr_per_cpu`` against the planned cost, ``cost.PlannedCost``); with
  ``sampling: lds`` all are the next LDS points.

The model is the map's model (``model.make_map_fit`` on the ``surrogate:`` config): what the step
calls converged is what results/maps draws.

Why an LDS share: active cases are not a uniform sample of the design space, so statistics of
the cases (the study's five statistics, their bootstrap CIs) would describe where the model was
unsure, not the design space.  Those two are computed on the LDS cases only (the start and the
LDS share of every batch, ``is_lds`` in the record), which stay a prefix of the LDS sequence;
the map criteria (CV RMSE, map change) use every case.

Everything the step needs is its arguments, so it is tested without Snakemake or YADE.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import pandas as pd

from ..case.identity import rounded
from ..design import NAMES, TARGETS, Design
from ..sampling import halton
from ..schema import checked
from ..study_rule.rule import DEFAULT_TOLERANCE, batches_until_converged
from ..table import usable
from . import active, map_criteria
from .model import FitFunction, make_map_fit


def step_settings(cfg: Mapping | None, targets: Sequence[str] | None = None) -> dict[str, Any]:
    """The ``converge:`` section with the schema's defaults filled (``spreadmap.schema.checked``;
    a partial section is completed, an unknown key or value refused), once for the whole step, and,
    under ``criteria``, the map criteria's settings picked from it (``map_criteria.criteria``, which
    checks the tolerances' targets)."""
    out = checked("converge", cfg)
    out["criteria"] = map_criteria.criteria(out, targets)
    return out


def cpu_hours(table: pd.DataFrame) -> float:
    """CPU hours of the cases: ``cpu_time`` (s), ``wall_time`` where it is missing."""
    cpu = pd.to_numeric(table.get("cpu_time", pd.Series(np.nan, index=table.index)), errors="coerce")
    wall = pd.to_numeric(table.get("wall_time", pd.Series(np.nan, index=table.index)), errors="coerce")
    return float(np.nansum(cpu.fillna(wall).to_numpy(float))) / 3600.0


def _lds_per_batch(s: Mapping) -> int:
    return int(s["batch"]) if s["sampling"] == "lds" else int(round(float(s["lds_share"]) * int(s["batch"])))


def _study_rule(table: pd.DataFrame, targets: Sequence[str], s: Mapping, n: int,
                tolerance: float, floors) -> dict[str, Any]:
    """The study's rule on the LDS cases (``table``), checked after every batch's LDS share.

    Its partitions are prefixes of the loop's own LDS rows in the order the loop ran them (the
    rows the steps marked ``is_lds``), not ``table.partition`` of a sweep's ``index``: the loop's
    LDS cases continue the sequence after the start, in its table's order. Usable: ``table.usable``.
    """
    ok = usable(table)
    values = np.where(ok[:, None], table[list(targets)].to_numpy(float), np.nan)
    res = batches_until_converged(lambda m: values[:m], batch_size=max(_lds_per_batch(s), 1),
                                  k_consecutive=int(s["k_consecutive"]), budget=n,
                                  start=min(int(s["start"]), n), tolerance=tolerance, floors=floors,
                                  names=tuple(targets))
    last = res["history"][-1]
    return {"rule": (f"all five statistics of {', '.join(targets)} change by < {tolerance:g} between "
                     f"batches, {s['k_consecutive']} batches in a row (the study's rule)"),
            "converged": res["reason"] == "converged", "converged_at": res["converged_n"],
            "max_change_now": last["max_change"], "streak_now": last["streak"]}


def step(table: pd.DataFrame, n: int, cfg: Mapping | None, prev_step: Mapping | None = None,
         fit: FitFunction | None = None, ranges: Design | Mapping | None = None, maps_cfg: Mapping | None = None,
         lds_seed: int = 42, targets: Sequence[str] = TARGETS,
         tolerance: float = DEFAULT_TOLERANCE, floors: Mapping | None = None,
         cost: Callable[[np.ndarray], np.ndarray] | None = None,
         models_out: dict | None = None) -> dict[str, Any]:
    """The decision after ``n`` cases: stop, or the next batch (see the module docstring).

    Parameters
    ----------
    table : pandas.DataFrame
        The results table's rows of the ``n`` cases, in run order, the previous step's ``n_prev``
        cases first.
    n : int
        Number of cases run; must equal ``len(table)``.
    cfg : Mapping or None
        The config's ``converge:`` section, whole or in part (the schema's defaults for what it
        leaves out).
    prev_step : Mapping or None, optional
        The previous step's record (its ``n``, ``is_lds``, criteria path and study-rule path);
        None for the first step (every case then counts as LDS).
    fit : FitFunction or None, optional
        The map model's fit function (``model.make_map_fit``); default: the surrogate's, default
        config.
    ranges : Design, mapping or None, optional
        The design space (``design.Design``, or the config's ``ranges``) for the map grids, the LDS points and the
        candidates.
    maps_cfg : Mapping or None, optional
        The config's ``maps:`` section, for the grids the map change is measured on.
    lds_seed : int, optional
        Seed of the LDS sequence the start and the LDS shares continue.
    targets : sequence of str, optional
        The targets modelled (results table columns).
    tolerance : float, optional
        The study's rule's tolerance (relative change between batches, 0.005 = 0.5 %).
    floors : Mapping or None, optional
        Per-target absolute floors of the study's rule (``study_rule.rule``), or None.
    cost : callable or None, optional
        Planned CPU seconds of cases at physical points X[n, 4] (``cost.PlannedCost``); needed by
        ``acquisition: ivr_per_cpu`` and used for the CPU budget (without it, the measured CPU
        decides the budget).
    models_out : dict or None, optional
        A dict that receives the fitted map models by target.

    Returns
    -------
    dict
        The JSON-ready step record: ``n``, ``usable``, ``cpu_hours`` and ``cpu_hours_modelled``
        (CPU h), ``stop`` and ``reason``, ``criteria``, ``study_rule`` and its path, ``next_n`` and
        ``next_batch`` (the next points, physical units), ``is_lds``, ``settings`` and ``summary``.

    Raises
    ------
    ValueError
        If a ``converge:`` setting is not allowed, ``len(table) != n``, a map-error tolerance
        names a target not in `targets`, ``ivr_per_cpu`` is asked for without `cost`, or the
        previous step lists another number of cases.
    """
    s = step_settings(cfg, targets)
    crit = s["criteria"]
    if len(table) != n:
        raise ValueError(f"the step after {n} cases got a table of {len(table)} rows")
    if s["sampling"] == "active" and s["acquisition"] == "ivr_per_cpu" and cost is None:
        raise ValueError("config key 'converge.acquisition': ivr_per_cpu needs the planned cost of a case (cost=)")
    fit = fit or make_map_fit()
    grids = map_criteria.map_grids(maps_cfg, ranges, box_k=int(crit["map_change"]["box_k"]))
    n_prev = None if prev_step is None else int(prev_step["n"])
    is_lds = [True] * n if prev_step is None else list(prev_step["is_lds"])
    if len(is_lds) != n:
        raise ValueError(f"the previous step lists {len(is_lds)} cases, the table has {n}")
    lds_table = table[np.asarray(is_lds, bool)]
    result = map_criteria.evaluate(table, fit, targets, None if n_prev is None else table.iloc[:n_prev],
                                   grids, crit, seed=0, floors=floors, stats_table=lds_table)
    if models_out is not None:
        models_out.update(result["models"])
    tracker = map_criteria.Tracker(crit["stop_on"], crit["hold_for"],
                                   None if prev_step is None else prev_step["criteria"]["path"],
                                   min_cases=crit["min_stop_cases"])
    tracker.add(n, result)
    cpu_h = cpu_hours(table)
    modelled_h = (float(np.sum(cost(table[list(NAMES)].to_numpy(float)))) / 3600.0 if cost is not None
                  else float("nan"))
    budget_h = modelled_h if cost is not None else cpu_h
    reason = None
    held_early = tracker.history[-1]["all_hold"] and n < tracker.min_cases
    if tracker.stop():
        reason = "criteria met"
    elif n >= int(s["budget"]):
        reason = "case budget"
    elif s["cpu_budget_h"] is not None and budget_h >= float(s["cpu_budget_h"]):
        reason = "CPU budget"
    record: dict[str, Any] = {
        "n": int(n), "usable": int(usable(table).sum()), "cpu_hours": cpu_h,
        "cpu_hours_modelled": modelled_h,
        "map_statistics": result.get("map_statistics", {}),
        "stop": reason is not None,
        "reason": reason or (f"criteria met, but a stop needs {tracker.min_cases} cases (converge.min_stop_cases)"
                             if held_early else "criteria not met yet"),
        "criteria": {**tracker.summary(), "at_this_batch": map_criteria.to_json(result)},
        "study_rule": _study_rule(lds_table, targets, s, len(lds_table), tolerance, floors),
        "study_rule_path": list((prev_step or {}).get("study_rule_path", [])),
        "next_n": None, "next_batch": [], "is_lds": is_lds, "n_lds": int(sum(is_lds)),
        "settings": {k: v for k, v in s.items() if k != "criteria"},
        "study_rule_tolerance": float(tolerance),
    }
    record["study_rule_path"].append({"n": int(n), "n_lds": int(len(lds_table)),
                                      "max_change": record["study_rule"]["max_change_now"],
                                      "streak": record["study_rule"]["streak_now"]})
    if reason is None:
        size = min(int(s["batch"]), int(s["budget"]) - n)
        fitted = all(t in result["models"] for t in targets)  # too few cases yet: the batch continues LDS
        k_lds = size if (s["sampling"] == "lds" or not fitted) else min(_lds_per_batch(s), size)
        n_lds = int(sum(is_lds))  # LDS points used so far: the next ones continue the sequence
        pts = halton(n_lds + k_lds, lds_seed, ranges)[list(NAMES)].to_numpy()[n_lds:]
        if k_lds < size:
            reference = np.vstack(list(grids.values()))
            models = [result["models"][t] for t in targets]
            acquisition = s["acquisition"]
            record["acquisition"] = acquisition
            more = active.choose_batch(models, size - k_lds, seed=int(s["seed"]) * 1_000_003 + n,
                                       done=table[list(NAMES)].to_numpy(float),
                                       n_candidates=int(s["candidates"]), acquisition=acquisition,
                                       reference=reference, ranges=ranges, pending=pts,
                                       cost=cost if acquisition == "ivr_per_cpu" else None)
            pts = np.vstack([pts, more])
        record["next_n"] = n + size
        record["next_batch"] = [rounded(dict(zip(NAMES, map(float, p)))) for p in pts]
        record["is_lds"] = is_lds + [True] * k_lds + [False] * (size - k_lds)
    record["summary"] = describe(record)
    return record


def describe(record: Mapping[str, Any]) -> str:
    """A few lines a user reads: why the run stopped (or not), how far each criterion is."""
    c = record["criteria"]
    modelled = record.get("cpu_hours_modelled")
    also = (f", {modelled:.2f} modelled" if modelled is not None and np.isfinite(modelled) else "")
    lines = [f"after {record['n']} cases ({record['usable']} usable, {record['cpu_hours']:.2f} CPU h measured{also}): "
             f"{record['reason']}"]
    for name in map_criteria.CRITERIA:
        now = c["now"].get(name)
        first = c["first_held"].get(name)
        req = "required" if name in c["stop_on"] else "reported"
        if now is None:
            lines.append(f"  {name} ({req}): not evaluated yet (needs a previous batch)")
            continue
        state = "holds" if now["holds"] else f"{now['value']:.3f} x its threshold"
        held = f"first held at {first} cases" if first is not None else "never held yet"
        targets = ((c.get("at_this_batch") or {}).get(name) or {}).get("targets") or {}
        scored = {t.get("scored") for t in targets.values()} - {None, "all cases"}
        note = f" (scored on {scored.pop()})" if name == "cv_rmse" and scored else ""
        if name == "map_error" and targets:
            note = " (" + "; ".join(
                f"{t}: {v['estimate']:.4f} of {v['tolerance']:.4f} [CV net of noise {v['cv_net_of_noise']:.4f}, "
                f"posterior {v['posterior_rms_sd']['worst']:.4f}]" for t, v in targets.items()) + ")"
        lines.append(f"  {name} ({req}): {state}{note}; {held}")
    sr = record["study_rule"]
    lines.append(f"  study's rule (reported): {'converged at ' + str(sr['converged_at']) if sr['converged'] else 'not converged'}"
                 + ("" if sr["max_change_now"] is None
                    or (isinstance(sr["max_change_now"], float) and math.isnan(sr["max_change_now"]))
                    else f"; largest change now {sr['max_change_now']:.4f}"))
    if record["next_n"]:
        lines.append(f"  next: {len(record['next_batch'])} cases ({record['settings']['sampling']}), up to {record['next_n']}")
    return "\n".join(lines)


def step_number(path: Path | str) -> int:
    """N of a step record's file name, results/converge/step_{N}.json (to order records by N,
    not as text: step_96 before step_112).

    Parameters
    ----------
    path : pathlib.Path or str
        A step record's path (only its name is read).

    Returns
    -------
    int
        The N after the last underscore of the file's stem.

    Raises
    ------
    IndexError
        If the stem has no underscore.
    ValueError
        If what follows the last underscore is not an integer.
    """
    return int(Path(path).stem.rsplit("_", 1)[1])
