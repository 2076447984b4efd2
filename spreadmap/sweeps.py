"""The cases the workflow registers for the config's sweeps (rules/common.smk), and the labels of
the main job's loop's cases in run order.

The plan (planned_cases): the first max(partitions) points of the seeded scrambled-Halton sequence
(`lds`), and the k^4 lattice of each k (`lattice`), at the sweep's preset (or the config's) and the
scene's packing seed; the same labels as the workflow's tables. The published study reads the
same plan (spreadlab.study.cases).
"""
from __future__ import annotations

from collections.abc import Iterator
from typing import NamedTuple

from .case.identity import case_id
from .case.render import template_sha256
from .design import Design
from .sampling import halton, lattice


class PlannedCase(NamedTuple):
    """A case of a sweep as the workflow registers it."""
    sweep: str  # "lds" or "lattice"
    point: dict  # the design point: a row of spreadmap.sampling.halton or lattice, with its "index"
    preset: str | None  # the sweep's preset; None: the config's
    label: dict  # its label in the sweep's table, without "sweep" (the workflow's register() adds it)
    case_id: str
    in_sweep: bool  # False for an LDS point past the sweep (there for the converge budget)


def planned_cases(config: dict, lds_points: int = 0, scene_sha256: str | None = None) -> Iterator[PlannedCase]:
    """The cases of the config's sweeps in the workflow's order.

    The LDS sequence up to the larger of its sweep and `lds_points` (the workflow's
    converge.budget), then the lattices by increasing k (a case shared by two lattices comes under
    each). Case ids are those of the scene template whose hash is scene_sha256 (default: the shipped
    template's).

    Parameters
    ----------
    config : dict
        The loaded configuration: ``sweeps`` (``lds``: ``partitions``, ``seed``, optional
        ``preset``; ``lattice``: ``k``, optional ``preset``), ``ranges``, ``preset``, ``scene.seed``
        and all a case id needs (``spreadmap.case.identity.case_id``).
    lds_points : int, optional
        LDS points to plan at least (the converge budget); those past the sweep's largest
        partition have ``in_sweep`` False.
    scene_sha256 : str or None, optional
        The hash of the scene template; None: that of the shipped template.

    Yields
    ------
    PlannedCase
        ``sweep`` ("lds" or "lattice"), ``point`` (the design point, physical units, with its
        ``index``), ``preset`` (None: the config's), ``label`` (``index``; for a lattice also ``k``
        and ``index_in_lattice``), ``case_id`` and ``in_sweep``.

    Raises
    ------
    spreadmap.case.scene.UnsafeTimeStep, ValueError
        For a case that must not run (``spreadmap.case.identity.case_scene``).
    """
    sweeps = config.get("sweeps") or {}
    space, seed = Design.from_config(config), config["scene"]["seed"]
    sha = template_sha256() if scene_sha256 is None else scene_sha256
    if "lds" in sweeps:
        preset, size = sweeps["lds"].get("preset"), max(sweeps["lds"]["partitions"])
        for row in halton(max(size, lds_points), sweeps["lds"]["seed"], space).to_dict("records"):
            yield PlannedCase("lds", row, preset, {"index": int(row["index"])},
                              case_id(row, preset or config["preset"], config, seed, sha), int(row["index"]) < size)
    if "lattice" in sweeps:
        preset = sweeps["lattice"].get("preset")
        rows = [(k, row) for k in sorted(set(sweeps["lattice"]["k"])) for row in lattice(k, space).to_dict("records")]
        for n, (k, row) in enumerate(rows):
            yield PlannedCase("lattice", row, preset, {"index": n, "k": k, "index_in_lattice": int(row["index"])},
                              case_id(row, preset or config["preset"], config, seed, sha), True)


def loop_labels(is_lds: list[bool], start: int, batch: int) -> list[dict]:
    """The labels of the loop's cases in run order in its table (the workflow's converge table and the study's).

    `sweep` converge, `index`, `batch` (0 for the LDS start, then 1, 2, ...) and `lds` (the LDS
    start and each batch's LDS share, or an active case).

    Parameters
    ----------
    is_lds : list of bool
        Per case in run order, whether it is an LDS case.
    start : int
        Cases in the LDS start (config ``converge.start``).
    batch : int
        Cases per batch after it (config ``converge.batch``).

    Returns
    -------
    list of dict
        One label per case: ``sweep``, ``index``, ``batch`` and ``lds``.
    """
    return [{"sweep": "converge", "index": i, "batch": 0 if i < start else 1 + (i - start) // batch, "lds": bool(lds)}
            for i, lds in enumerate(is_lds)]
