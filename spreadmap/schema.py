"""The config's JSON schema (schemas/config.schema.yaml): one section of it, and one section checked
alone with its defaults filled.

The ground floor of the package's configuration: any module may read its defaults here without
importing the whole config's validation (``spreadmap.config``, which checks the keys that refer
to each other and so imports the modules that own them). The schema is the one place a default
is stated.
"""
from __future__ import annotations

import copy
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path

import jsonschema
import yaml

SCHEMA = Path(__file__).resolve().parent.parent / "schemas" / "config.schema.yaml"
# libyaml's parser where PyYAML was built with it (the same documents, ~7x faster: 0.04 s for the
# schema against 0.26 s); PyYAML's own otherwise
YAML_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def read_yaml(text: str):
    """A YAML document as ``yaml.safe_load`` reads it (libyaml's parser where there is one)."""
    return yaml.load(text, Loader=YAML_LOADER)


@lru_cache(maxsize=None)
def whole_schema() -> dict:
    """The whole JSON schema (schemas/config.schema.yaml), read once a process; do not modify it."""
    return read_yaml(SCHEMA.read_text())


@lru_cache(maxsize=None)
def section_schema(name: str) -> dict:
    """The JSON schema of one config section (read once; do not modify it).

    Parameters
    ----------
    name : str
        The section: a top-level key of schemas/config.schema.yaml (e.g. "maps"), or a dotted path
        to an object inside one (e.g. "scene.substrate").

    Returns
    -------
    dict
        The section's schema, the same object at every call (cached).

    Raises
    ------
    KeyError
        If the schema has no such section.
    """
    head, _, rest = name.rpartition(".")
    parent = section_schema(head) if head else whole_schema()
    return parent["properties"][rest]


def _fill_defaults(schema: dict, value: dict) -> dict:
    for key, sub in schema.get("properties", {}).items():
        if key not in value and "default" in sub:
            value[key] = copy.deepcopy(sub["default"])
        if sub.get("type") == "object" and "properties" in sub:
            value[key] = _fill_defaults(sub, dict(value.get(key) or {}))
    return value


def checked(name: str, section: Mapping | None = None) -> dict:
    """One config section validated against its schema with the schema's defaults filled (a copy).

    For code that is handed a section, or none, rather than a loaded config. (Sections that $ref the
    schema's definitions, e.g. noise_model, cannot be checked alone.)

    Parameters
    ----------
    name : str
        The section: a top-level key of the schema, or a dotted path to an object inside one
        (e.g. "scene.substrate", for code handed that part of a config).
    section : Mapping or None, optional
        The section's values; {} or None: the defaults alone. Not modified.

    Returns
    -------
    dict
        A copy of the section with the schema's defaults filled (in nested objects too).

    Raises
    ------
    ValueError
        If the section does not match its schema; the message names the key (or the unknown keys
        and the known ones).
    """
    schema = section_schema(name)
    value = copy.deepcopy(dict(section or {}))
    error = jsonschema.exceptions.best_match(jsonschema.Draft202012Validator(schema).iter_errors(value))
    if error is not None:
        where = ".".join(str(p) for p in error.absolute_path)
        if error.validator == "additionalProperties":
            extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
            raise ValueError(f"unknown {name} config key(s) {extra}; known: {sorted(error.schema['properties'])}")
        raise ValueError(f"{name}.{where}: {error.message}")
    return _fill_defaults(schema, value)
