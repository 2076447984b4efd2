"""The ``decisions:`` config section: defaults from schemas/config.schema.yaml, and the checks a
schema cannot express (ranges inside the design space, targets the surrogate can have). Every
problem names its key."""
from __future__ import annotations

from collections.abc import Mapping

from .. import targets as registry
from ..design import NAMES, bounds
from ..schema import checked


class DecisionError(ValueError):
    """A decisions setting that cannot be answered: the message names the config key."""


def decision_config(config: Mapping | None = None) -> dict:
    """The ``decisions:`` section validated against the schema, defaults filled.

    Parameters
    ----------
    config : Mapping or None, optional
        The config's ``decisions:`` section; None or empty: all defaults.

    Returns
    -------
    dict
        A copy with the schema's defaults filled in (``powders``, ``machine``, ``bounds``,
        ``quality``, ``confidence``, ``about``, ``draws``, ...).

    Raises
    ------
    ValueError
        If the section breaks the schema (schemas/config.schema.yaml); the message names the key.
    """
    return checked("decisions", config)


def span(value) -> tuple[float, float]:
    """A powder parameter as (low, high): one value gives (value, value)."""
    if isinstance(value, (list, tuple)):
        return float(value[0]), float(value[1])
    return float(value), float(value)


def possible_targets(config: Mapping) -> list[str]:
    """The targets the surrogate can have under this (validated) config's ``surrogate.targets``."""
    spec = config["surrogate"]["targets"]
    return list(registry.names()) if spec == "auto" else list(spec)


def problems(config: Mapping) -> list[str]:
    """What is wrong with the config's ``decisions:`` section beyond its schema (each message
    names the key). Design-space limits come from the config's ``ranges``."""
    if "decisions" not in config:
        return []
    dec = decision_config(config["decisions"])
    low, high = bounds(config.get("ranges"))
    limits = {name: (lo, hi) for name, lo, hi in zip(NAMES, low, high)}
    out = []

    def inside(key, name, lo, hi):
        if lo > hi:
            out.append(f"config key '{key}': the range [{lo:g}, {hi:g}] is reversed; write it low to high")
        elif lo < limits[name][0] or hi > limits[name][1]:
            out.append(f"config key '{key}': [{lo:g}, {hi:g}] reaches outside the design space "
                       f"(ranges.{name}: {limits[name][0]:g} to {limits[name][1]:g})")

    for name in ("h_um", "v_mm_s"):
        lo, hi = dec["machine"][name]
        if lo == hi:
            out.append(f"config key 'decisions.machine.{name}': [{lo:g}, {hi:g}] is one value; give the machine's range")
        inside(f"decisions.machine.{name}", name, lo, hi)
    for powder, spec in dec["powders"].items():
        for name in ("f", "d_um"):
            inside(f"decisions.powders.{powder}.{name}", name, *span(spec[name]))
    allowed = possible_targets(config)
    for target, bound in dec["bounds"].items():
        if target not in allowed:
            out.append(f"config key 'decisions.bounds.{target}': {target!r} is not a target the surrogate can have "
                       f"(surrogate.targets: {allowed})")
        if "min" in bound and "max" in bound and not bound["min"] < bound["max"]:
            out.append(f"config key 'decisions.bounds.{target}': min {bound['min']:g} must be below max {bound['max']:g}")
    if dec["quality"]["target"] not in allowed:
        out.append(f"config key 'decisions.quality.target': {dec['quality']['target']!r} is not a target the "
                   f"surrogate can have (surrogate.targets: {allowed})")
    return out
