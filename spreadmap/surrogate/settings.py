"""The surrogate's configuration: the `surrogate:` section of config.yaml, its defaults read from
schemas/config.schema.yaml (one place states them; spreadmap.schema.checked), checked without
importing scikit-learn."""
from __future__ import annotations

from collections.abc import Mapping

from .. import targets as registry
from ..schema import checked


def make_config(config: Mapping | None = None) -> dict:
    """The surrogate's effective configuration (defaults from the schema, unknown keys refused)."""
    return checked("surrogate", config)


def problems(config: Mapping) -> list[str]:
    """What is wrong with a whole config's ``surrogate:`` section (its defaults filled, unknown keys
    refused: ``make_config``), as a message naming the key; spreadmap.config.validate asks it."""
    try:
        make_config(config["surrogate"])
    except (ValueError, KeyError) as error:
        return [f"config key 'surrogate': {error}"]
    return []


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
    """The targets to model: ``auto`` = every target of ``spreadmap.targets`` whose column the
    table has (mfr, pd and the layer-quality measures), in registry order; or the list given."""
    columns = set(columns)
    if spec == "auto":
        return [t for t in registry.names() if t in columns]
    missing = [t for t in spec if t not in columns]
    if missing:
        raise ValueError(f"surrogate.targets: column(s) {missing} not in the results table")
    return list(spec)
