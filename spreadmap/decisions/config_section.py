"""The ``decisions:`` config section: defaults from schemas/config.schema.yaml, and the checks a
schema cannot express (ranges inside the design space, targets the surrogate can have). Every
problem names its key."""
from __future__ import annotations

from collections.abc import Mapping

from .. import targets as registry
from ..design import NAMES, bounds
from ..schema import checked
from ..slices import DECISIONS


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


def powder_size(spec: Mapping) -> tuple[tuple[float, float], float | None]:
    """A powder's size as the maps read it: its D50 as (low, high) [um] and the span it states.

    Parameters
    ----------
    spec : Mapping
        One powder of ``decisions.powders`` (schema-checked): ``d_um`` (one value or a range; one
        size, or the D50 of the study's distribution), or ``d50_um`` with ``d10_um`` and
        ``d90_um`` (a certificate) or with ``span``.

    Returns
    -------
    tuple
        ((low, high) of the D50, span): the span is (D90 - D10) / D50 of a certificate, the
        ``span`` given, or None when the powder states none (it is then taken to have the study's).
    """
    if "d_um" in spec:
        return span(spec["d_um"]), (float(spec["span"]) if "span" in spec else None)
    d50 = float(spec["d50_um"])
    if "d10_um" in spec and "d90_um" in spec:
        return (d50, d50), (float(spec["d90_um"]) - float(spec["d10_um"])) / d50
    return (d50, d50), (float(spec["span"]) if "span" in spec else None)


def powder_problems(name: str, spec: Mapping, study_span: float, tolerance: float) -> list[str]:
    """What is wrong with one powder beyond its schema: a certificate out of order or half given,
    a span given twice, a span the study's maps do not speak for (span is not a design axis)."""
    key = f"config key 'decisions.powders.{name}'"
    given = [k for k in ("d10_um", "d90_um") if k in spec]
    if len(given) == 1:
        return [f"{key}: {given[0]} without {({'d10_um', 'd90_um'} - set(given)).pop()}; give both, or the span"]
    if given and ("d_um" in spec or "span" in spec):
        return [f"{key}: d10_um and d90_um go with d50_um and without span (the span is (D90 - D10) / D50)"]
    if given and not spec["d10_um"] < spec["d50_um"] < spec["d90_um"]:
        return [f"{key}: D10 {spec['d10_um']:g}, D50 {spec['d50_um']:g}, D90 {spec['d90_um']:g} um must rise"]
    _, stated = powder_size(spec)
    if stated is not None and abs(stated - study_span) > tolerance:
        what = "one size" if study_span == 0 else f"span {study_span:g}"
        return [f"{key}: span {stated:.2f} but the study's spheres are {what} (material.size_distribution.span "
                f"{study_span:g}; decisions.span_tolerance {tolerance:g}): span is not a design axis, so the maps do "
                f"not speak for this powder. Run the study with material.size_distribution.span: {stated:.2f}, "
                f"or give the powder by d_um alone"]
    return []


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

    for name in DECISIONS.varying:
        lo, hi = dec["machine"][name]
        if lo == hi:
            out.append(f"config key 'decisions.machine.{name}': [{lo:g}, {hi:g}] is one value; give the machine's range")
        inside(f"decisions.machine.{name}", name, lo, hi)
    study_span = float(((config.get("material") or {}).get("size_distribution") or {}).get("span", 0.0))
    for powder, spec in dec["powders"].items():
        inside(f"decisions.powders.{powder}.f", "f", *span(spec["f"]))
        size_key = "d_um" if "d_um" in spec else "d50_um"
        inside(f"decisions.powders.{powder}.{size_key}", "d_um", *powder_size(spec)[0])
        out += powder_problems(powder, spec, study_span, dec["span_tolerance"])
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
