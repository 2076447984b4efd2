"""The surrogate's configuration: the `surrogate:` section of config.yaml, its defaults read from
schemas/config.schema.yaml (one place states them), checked without importing scikit-learn."""
from __future__ import annotations

import copy
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path

import jsonschema
import yaml

SCHEMA = Path(__file__).resolve().parents[2] / "schemas" / "config.schema.yaml"
LAYER_TARGETS = ("layer_packing", "coverage", "roughness_d", "thickness_ratio")
BASE_TARGETS = ("mfr", "pd")


@lru_cache(maxsize=None)
def section_schema(name: str) -> dict:
    """The JSON schema of one top-level config section (``surrogate`` or ``maps``)."""
    return yaml.safe_load(SCHEMA.read_text())["properties"][name]


def _fill_defaults(schema: dict, value: dict) -> dict:
    for key, sub in schema.get("properties", {}).items():
        if key not in value and "default" in sub:
            value[key] = copy.deepcopy(sub["default"])
        if sub.get("type") == "object" and "properties" in sub:
            value[key] = _fill_defaults(sub, dict(value.get(key) or {}))
    return value


def checked(name: str, config: Mapping | None) -> dict:
    """A config section validated against its schema, defaults filled; ValueError names the key."""
    schema = section_schema(name)
    value = copy.deepcopy(dict(config or {}))
    error = jsonschema.exceptions.best_match(jsonschema.Draft202012Validator(schema).iter_errors(value))
    if error is not None:
        where = ".".join(str(p) for p in error.absolute_path)
        if error.validator == "additionalProperties":
            extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
            raise ValueError(f"unknown {name} config key(s) {extra}; known: {sorted(error.schema['properties'])}")
        raise ValueError(f"{name}.{where}: {error.message}")
    return _fill_defaults(schema, value)


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
