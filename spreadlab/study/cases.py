"""The study's sweeps as planned by a configuration, and the table of the cases of a workflow
directory that have finished so far (docs/study is published from it while the study grows).

The plan is the one rules/common.smk registers (spreadmap.sweeps.planned_cases); the same labels as
the workflow's tables.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from spreadmap.case.identity import case_id, is_legacy_id, readable_part
from spreadmap.case.render import template_sha256
from spreadmap.design import NAMES
from spreadmap.sweeps import PlannedCase, loop_labels, planned_cases  # noqa: F401  (PlannedCase, re-exported)
from spreadmap.table import build_table


def planned_sweeps(config: dict, scene_sha256: str | None = None) -> dict[str, list[tuple[str, dict]]]:
    """The planned cases of each sweep the config has, with the labels of the workflow's tables.

    Parameters
    ----------
    config : dict
        The loaded configuration (``planned_cases``).
    scene_sha256 : str or None, optional
        The hash of the scene template the ids are for; None: that of the shipped template.

    Returns
    -------
    dict of str to list of (str, dict)
        ``{"lds": [(case id, label)], "lattice": [...]}`` for the sweeps the config has, each label
        with its ``sweep``; the LDS planned up to its sweep's largest partition.
    """
    plan = {name: [] for name in ("lds", "lattice") if name in (config.get("sweeps") or {})}
    for case in planned_cases(config, scene_sha256=scene_sha256):
        plan[case.sweep].append((case.case_id, {"sweep": case.sweep, **case.label}))
    return plan


def loop_cases(config: dict, steps: list[dict], scene_sha256: str | None = None) -> list[tuple[str, dict]]:
    """The main job's loop so far as (case id, label), in run order, from its step records.

    The step records are the converge checkpoints, ordered by n: the LDS start, then each step's
    next batch; labels as the workflow's converge table (`sweep` converge, `index`, `batch`, `lds`).

    Parameters
    ----------
    config : dict
        The loaded configuration: ``converge.start`` and ``converge.batch``, the LDS sweep's preset
        (else ``preset``), ``scene.seed`` and all a case id needs.
    steps : list of dict
        The loop's step records (converge/steps/step_N.json): ``n``, ``next_batch`` (design
        points, physical units) and ``is_lds`` (per case so far, in run order); any order.
    scene_sha256 : str or None, optional
        The hash of the scene template the ids are for; None: that of the shipped template.

    Returns
    -------
    list of (str, dict)
        (case id, label) per case in run order (``loop_labels``); without steps, the LDS start
        alone.
    """
    start, batch = int(config["converge"]["start"]), int(config["converge"]["batch"])  # a loaded config: filled
    preset = ((config.get("sweeps") or {}).get("lds") or {}).get("preset") or config["preset"]
    seed, sha = config["scene"]["seed"], template_sha256() if scene_sha256 is None else scene_sha256
    ids = [c.case_id for c in planned_cases(config, lds_points=start, scene_sha256=sha) if c.sweep == "lds"][:start]
    for step in sorted(steps, key=lambda s: int(s["n"])):
        ids += [case_id(point, preset, config, seed, sha) for point in step.get("next_batch", [])]
    is_lds = max(steps, key=lambda s: int(s["n"]))["is_lds"] if steps else [True] * len(ids)
    return list(zip(ids, loop_labels(is_lds[:len(ids)], start, batch)))


def finished_table(workdir: Path | str, planned: list[tuple[str, dict]]) -> pd.DataFrame:
    """The results table of the planned cases whose metrics exist in workdir/results/cases, in plan order.

    A case shared by two lattices appears under each of its labels, as in the workflow.

    Parameters
    ----------
    workdir : pathlib.Path or str
        The workflow directory.
    planned : list of (str, dict)
        (case id, label) in plan order (``planned_sweeps``' list of one sweep, or ``loop_cases``).

    Returns
    -------
    pandas.DataFrame
        ``spreadmap.table.build_table`` of the finished cases' metrics.json and benchmark.tsv, with
        their labels.

    Raises
    ------
    spreadmap.records.CorruptFileError
        If a finished case's metrics.json is not a whole metrics record.
    """
    cases = Path(workdir) / "results" / "cases"
    done = [(cid, label) for cid, label in planned if (cases / cid / "metrics.json").exists()]
    return build_table([cases / cid / "metrics.json" for cid, _ in done],
                       [cases / cid / "benchmark.tsv" for cid, _ in done], [label for _, label in done])


def cpu_hours_to_go(config: dict, tables: dict[str, pd.DataFrame], scene_sha256: str | None = None) -> dict[str, float]:
    """Per sweep: the predicted CPU hours of its planned cases not yet finished.

    From the planned-cost law (spreadmap.loop.cost) calibrated to the finished cases' measured CPU
    (this machine's speed); a case shared by two sweeps counts in each. A table published before
    content keys names its cases by their readable part: a planned case of that readable part counts
    as finished.

    Parameters
    ----------
    config : dict
        The loaded configuration (the plan, ``planned_cases``, and the cost law,
        ``PlannedCost.from_config``).
    tables : dict of str to pandas.DataFrame
        Per sweep, its finished cases' table (``case_id``, the design point and ``cpu_time`` [s]).
    scene_sha256 : str or None, optional
        The hash of the scene template the ids are for; None: that of the shipped template.

    Returns
    -------
    dict of str to float
        Per sweep of ``tables``: the CPU hours [h] of its planned cases still to run (0.0 if none).
    """
    nonempty = [t for t in tables.values() if len(t)]
    finished = pd.concat(nonempty, ignore_index=True) if nonempty else pd.DataFrame()
    done = set(finished["case_id"]) if "case_id" in finished else set()
    # a table published before content keys (issue 35) names its cases by their readable part only
    legacy = {cid for cid in done if is_legacy_id(cid)}
    todo: dict[str, dict[str, dict]] = {name: {} for name in tables}
    for case in planned_cases(config, scene_sha256=scene_sha256):
        if case.sweep in todo and case.case_id not in done and readable_part(case.case_id) not in legacy:
            todo[case.sweep][case.case_id] = case.point
    from spreadmap.loop.cost import PlannedCost  # here: the workflow's registry imports this module

    cost = PlannedCost.from_config(config)
    if "case_id" in finished:
        cost = cost.calibrated(finished.drop_duplicates("case_id"))
    out = {}
    for name, points in todo.items():
        X = pd.DataFrame(list(points.values()), columns=list(NAMES)).to_numpy(float)
        out[name] = float(cost(X).sum()) / 3600.0 if len(X) else 0.0
    return out


def progress(planned: dict[str, list[tuple[str, dict]]], tables: dict[str, pd.DataFrame],
             to_go: dict[str, float] | None = None) -> pd.DataFrame:
    """Per sweep: cases planned, finished, usable-status counts and their CPU hours.

    Given ``to_go`` from cpu_hours_to_go, also the predicted CPU hours of the rest. A case shared by
    two lattices ran once and counts once.

    Parameters
    ----------
    planned : dict of str to list of (str, dict)
        Per sweep, its planned (case id, label) (``planned_sweeps``).
    tables : dict of str to pandas.DataFrame
        Per sweep, its finished cases' table (``finished_table``).
    to_go : dict of str to float or None, optional
        Per sweep, the CPU hours still to run (``cpu_hours_to_go``); None: no such column.

    Returns
    -------
    pandas.DataFrame
        One row per sweep: ``sweep``, ``planned``, ``finished``, ``ok``, ``failed`` (finished, status
        not ok), ``cpu_hours`` [h] (of the finished cases, 3 decimals) and, with ``to_go``,
        ``cpu_hours_to_go`` [h] (1 decimal).
    """
    rows = []
    for name, plan in planned.items():
        table = tables[name]
        unique = table.drop_duplicates("case_id") if "case_id" in table else table  # a case shared by two lattices ran once
        status = unique["status"] if "status" in unique else pd.Series(dtype=str)
        cpu = unique["cpu_time"].sum() / 3600.0 if "cpu_time" in unique else 0.0
        rows.append({"sweep": name, "planned": len({cid for cid, _ in plan}),
                     "finished": len(unique) if "case_id" in table else 0,
                     "ok": int((status == "ok").sum()), "failed": int((status != "ok").sum()),
                     "cpu_hours": round(float(cpu), 3)})
        if to_go is not None:
            rows[-1]["cpu_hours_to_go"] = round(float(to_go[name]), 1)
    return pd.DataFrame(rows)
