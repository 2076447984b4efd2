"""Which cases the fidelity study runs (config `fidelity:`): every reference point at every preset
with every packing seed, and the one-knob-at-a-time sweeps at one point.

A knob value is a preset of its own: the base preset with that one key changed, named
``{base}_{knob}_{value}`` (e.g. ``default_dt_factor_0p15``), so that its cases carry what they
are in their ids and in the results table like any other preset's. The base preset's own value
is part of every knob's sweep: those cases are the base preset's, shared, run once.
"""
from __future__ import annotations

import copy

from ..design import NAMES

# The keys of a preset the knob sweeps may turn.
KNOBS = ("width_d", "heap_height_d", "pile_length_min_d", "heap_reserve", "transient_d", "window_d",
         "dt_factor", "density_scale", "target_cv")


def value_token(value: float) -> str:
    """A value as it appears in a preset name: 0.15 -> 0p15, 10000 -> 10000, 1e-05 -> 1em05."""
    return f"{value:g}".replace(".", "p").replace("+", "").replace("-", "m")


def knob_preset_name(base: str, knob: str, value: float) -> str:
    return f"{base}_{knob}_{value_token(value)}"


def knob_presets(config: dict) -> dict[str, dict]:
    """The presets of the knob sweeps, by name: {name: preset} (the base preset's own values excluded)."""
    knobs = (config.get("fidelity") or {}).get("knobs")
    if not knobs:
        return {}
    base = knobs["preset"]
    out = {}
    for knob, values in knobs["values"].items():
        for value in values:
            if value == config["presets"][base][knob]:
                continue
            preset = copy.deepcopy(config["presets"][base])
            preset[knob] = value
            preset["description"] = f"{base} with {knob} = {value:g} (fidelity knob sweep)"
            out[knob_preset_name(base, knob, value)] = preset
    return out


def preset_cases(config: dict) -> list[dict]:
    """The preset comparison: one row per (point, preset, seed), the reference preset last."""
    fid = config["fidelity"]
    presets = [p for p in fid["presets"] if p != fid["reference"]] + [fid["reference"]]
    return [{"name": name, "point": point, "preset": preset, "seed": seed}
            for name, point in fid["points"].items() for preset in presets for seed in fid["seeds"]]


def knob_cases(config: dict) -> list[dict]:
    """The knob sweeps: one row per (knob, value, seed) at the knob point, the base value included."""
    fid = config["fidelity"]
    knobs = fid.get("knobs")
    if not knobs:
        return []
    base = knobs["preset"]
    point = fid["points"][knobs["point"]]
    rows = []
    for knob, values in knobs["values"].items():
        base_value = config["presets"][base][knob]
        for value in sorted({*values, base_value}):
            preset = base if value == base_value else knob_preset_name(base, knob, value)
            for seed in knobs["seeds"]:
                rows.append({"name": knobs["point"], "point": point, "preset": preset, "seed": seed,
                             "knob": knob, "value": float(value), "is_base": value == base_value})
    return rows


def check(config: dict) -> list[str]:
    """Problems of the `fidelity:` section that the schema cannot see, as messages naming the key."""
    fid = config.get("fidelity")
    if not fid:
        return []
    presets = config["presets"]
    problems = []
    if fid["reference"] not in presets:
        problems.append(f"config key 'fidelity.reference': value {fid['reference']!r} is not allowed; "
                        f"it must be one of the presets defined: {sorted(presets)}")
    if fid["reference"] not in fid["presets"]:
        problems.append(f"config key 'fidelity.presets': value {fid['presets']} is not allowed; "
                        f"it must include the reference preset {fid['reference']!r}")
    for name in fid["presets"]:
        if name not in presets:
            problems.append(f"config key 'fidelity.presets': value {name!r} is not allowed; "
                            f"it must be one of the presets defined: {sorted(presets)}")
    for name, point in fid["points"].items():
        extra = sorted(set(point) - set(NAMES))
        if extra:
            problems.append(f"config key 'fidelity.points.{name}': keys {extra} are not allowed; a fidelity point "
                            f"is run at every preset of fidelity.presets and every seed of fidelity.seeds")
    knobs = fid.get("knobs")
    if knobs:
        if knobs["point"] not in fid["points"]:
            problems.append(f"config key 'fidelity.knobs.point': value {knobs['point']!r} is not allowed; "
                            f"it must name one of fidelity.points: {sorted(fid['points'])}")
        if knobs["preset"] not in presets:
            problems.append(f"config key 'fidelity.knobs.preset': value {knobs['preset']!r} is not allowed; "
                            f"it must be one of the presets defined: {sorted(presets)}")
        for name in knob_presets(config) if not problems else []:
            if name in presets:
                problems.append(f"config key 'presets.{name}': the name is taken by a knob-sweep preset of "
                                f"fidelity.knobs; rename the preset")
    return problems
