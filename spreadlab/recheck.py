"""A published loop's steps decided again with another noise law, from its cases (no DEM).

The loop's criteria read each case's noise SD (``spreadmap.noise_law.apply.case_noise``: the
config's ``noise_model``): the GP's per-case noise, the CV error net of the noise and the batch's
choice all depend on it. ``recheck_path`` takes a run's cases in its run order and its step records,
and at every step's number of cases calls the loop's own ``stepper.step`` on the first n cases with
the given ``noise_model``, each step given the previous re-decided step (its criteria path, so the
stop rule's ``hold_for`` counts re-decided batches) and the run's own LDS flags. The cases stay the
run's: where the re-decided loop would have chosen other cases, or stopped, the later steps answer
"what would it have said of these cases", not "what would it have run".
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Mapping, Sequence

import pandas as pd

from spreadmap.loop.cost import PlannedCost
from spreadmap.loop.model import make_map_fit
from spreadmap.loop.stepper import step, step_number
from spreadmap.noise_law.apply import case_noise


def run_steps(run_dir: Path | str) -> list[dict]:
    """The step records ``step_*.json`` of a run's folder, in order of their number of cases.

    Parameters
    ----------
    run_dir : pathlib.Path or str
        A folder holding the loop's step records (results/converge, or a published run's copy).

    Returns
    -------
    list of dict
        The records, fewest cases first.

    Raises
    ------
    ValueError
        If the folder holds no step record.
    """
    paths = sorted(Path(run_dir).glob("step_*.json"), key=step_number)
    if not paths:
        raise ValueError(f"{run_dir}: no loop step records (step_*.json)")
    return [json.loads(p.read_text()) for p in paths]


def redecide(cases: pd.DataFrame, n: int, cfg: Mapping, previous: Mapping | None, fit=None, cost=None) -> dict:
    """The loop's own step (``stepper.step``) after the first `n` of `cases` (their noise SDs already
    set), with the run's config: what the loop would decide there.

    Parameters
    ----------
    cases : pandas.DataFrame
        The cases in run order, with their noise SDs (``case_noise``).
    n : int
        How many of them the step has seen.
    cfg : Mapping
        The run's validated config (``converge``, ``surrogate``, ``ranges``, ``maps``, ``sweeps``,
        ``study_rule`` and what ``PlannedCost`` reads).
    previous : Mapping or None
        The step before it (None: the first step).
    fit, cost : optional
        The map fit and the cost law to use (default: the config's, built anew).

    Returns
    -------
    dict
        The step record.
    """
    return step(cases, n, cfg["converge"], previous,
                fit=fit if fit is not None else make_map_fit(cfg["surrogate"], final=True), ranges=cfg["ranges"],
                maps_cfg=cfg["maps"], lds_seed=cfg["sweeps"]["lds"]["seed"], tolerance=cfg["study_rule"]["tolerance"],
                floors=cfg["study_rule"].get("floors"), cost=cost if cost is not None else PlannedCost.from_config(cfg))


def recheck_path(table: pd.DataFrame, cfg: Mapping, steps: Sequence[Mapping], noise_model: Mapping | None,
                 noise_calibration: list | None = None) -> list[dict]:
    """Every step of a run decided again with `noise_model` (see the module docstring).

    Parameters
    ----------
    table : pandas.DataFrame
        The run's cases in run order (the converge table: the first n rows are the cases of the
        step after n), with the columns the loop reads (design, targets, stated SDs, counts).
    cfg : Mapping
        The run's validated config (``converge``, ``surrogate``, ``ranges``, ``maps``, ``sweeps``,
        ``study_rule``, ``metrics``, ``noise_calibration`` and what ``PlannedCost`` reads); its
        ``noise_model`` is not read.
    steps : sequence of Mapping
        The run's step records, in order (``run_steps``).
    noise_model : Mapping or None
        The ``noise_model`` section the steps are decided with (None: the stated counting SDs).
    noise_calibration : list or None, optional
        The ``noise_calibration`` regions; default the config's.

    Returns
    -------
    list of dict
        The re-decided step records (``stepper.step``), one per published step.

    Raises
    ------
    ValueError
        If the table has fewer rows than a step's cases, or a step's LDS flags disagree with the
        previous step's.
    """
    calibration = cfg["noise_calibration"] if noise_calibration is None else noise_calibration
    fit = make_map_fit(cfg["surrogate"], final=True)
    cost = PlannedCost.from_config(cfg)
    out: list[dict] = []
    previous = None
    for published in steps:
        n = int(published["n"])
        if len(table) < n:
            raise ValueError(f"the step after {n} cases, the cases table has {len(table)} rows")
        cases = case_noise(table.iloc[:n].reset_index(drop=True), noise_model, calibration,
                           cfg["metrics"]["counting_noise_c"])
        if previous is not None:
            # the run's own LDS flags of these n cases (a re-decided step that stopped lists none beyond its n)
            flags = list(published["is_lds"][:n])
            if list(previous["is_lds"][:int(previous["n"])]) != flags[:int(previous["n"])]:
                raise ValueError(f"the step after {n} cases: its LDS flags differ from the step before it")
            previous = {**previous, "is_lds": flags}
        record = redecide(cases, n, cfg, previous, fit=fit, cost=cost)
        out.append(record)
        previous = record
    return out


def path_rows(records: Sequence[Mapping], label: str) -> list[dict]:
    """One row per re-decided step: its map-error ratio (the stop criterion), each target's
    estimate, CV error net of noise and posterior SD, the CV noise it nets out, and the decision.

    Parameters
    ----------
    records : sequence of Mapping
        Step records (``recheck_path``, or a run's own).
    label : str
        The noise law's name, in the ``law`` column.

    Returns
    -------
    list of dict
        ``law``, ``n``, ``map_error_ratio``, ``stop``, ``reason`` and, per target t,
        ``t_estimate``, ``t_cv_net_of_noise``, ``t_posterior``, ``t_cv_rmse``, ``t_cv_noise_sd``.
    """
    rows = []
    for rec in records:
        crit = rec["criteria"]["at_this_batch"]
        row = {"law": label, "n": int(rec["n"]), "map_error_ratio": crit["map_error"]["value"],
               "stop": bool(rec["stop"]), "reason": rec["reason"]}
        for t, v in crit["map_error"]["targets"].items():
            cv = crit["cv_rmse"]["targets"][t]
            row.update({f"{t}_estimate": v["estimate"], f"{t}_cv_net_of_noise": v["cv_net_of_noise"],
                        f"{t}_posterior": v["posterior_rms_sd"]["worst"], f"{t}_cv_rmse": cv["rmse"],
                        f"{t}_cv_noise_sd": cv["noise_sd"]})
        rows.append(row)
    return rows
