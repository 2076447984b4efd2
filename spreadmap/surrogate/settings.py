"""The surrogate's configuration: the `surrogate:` section of config.yaml, its defaults read from
schemas/config.schema.yaml (one place states them; spreadmap.schema.checked), checked without
importing scikit-learn."""
from __future__ import annotations

from collections.abc import Mapping

from ..schema import checked

LAYER_TARGETS = ("layer_packing", "coverage", "roughness_d", "thickness_ratio")
BASE_TARGETS = ("mfr", "pd")


def make_config(config: Mapping | None = None) -> dict:
    """The surrogate's effective configuration (defaults from the schema, unknown keys refused)."""
    return checked("surrogate", config)


def map_config(config: Mapping | None = None) -> dict:
    """The maps' effective configuration (``sobol_n``: a power of 2, listed in the schema).

    Parameters
    ----------
    config : Mapping or None, optional
        The config's ``maps:`` section (or part of it, e.g. ``{"support": ...}``); None: all
        defaults.

    Returns
    -------
    dict
        A copy with the schema's defaults filled in (``support``, ``sobol_n``, ...).

    Raises
    ------
    ValueError
        If the section breaks the schema (schemas/config.schema.yaml); the message names the key.
    """
    return checked("maps", config)


def resolve_targets(spec, columns) -> list[str]:
    """The targets to model: ``auto`` = mfr, pd and the layer-quality columns present."""
    columns = set(columns)
    if spec == "auto":
        return [t for t in (*BASE_TARGETS, *LAYER_TARGETS) if t in columns]
    missing = [t for t in spec if t not in columns]
    if missing:
        raise ValueError(f"surrogate.targets: column(s) {missing} not in the results table")
    return list(spec)
