"""Load and validate config.yaml: Snakemake's `validate` against schemas/config.schema.yaml
(which also fills defaults), then the checks a schema cannot express. Every error names the key,
the bad value and what is allowed, in one line."""
from __future__ import annotations

import copy
import warnings
from pathlib import Path

import jsonschema

# the schema, a section of it and a section checked alone live in spreadmap.schema (the ground
# floor every module may read); this module validates a whole config, cross-keys included (the
# sections of later stages by the checks their owners hand in: SECTION_CHECKS)
from .schema import SCHEMA, checked, read_yaml, section_schema  # noqa: F401  (re-exported)
from .targets import REGISTRY
from .targets import RENAMED as RENAMED_TARGETS
from .targets import names as target_names

# The checks of the sections the later stages own (surrogate, decisions, fidelity): each owner
# states what is wrong with its section, `check(config) -> list of messages naming the key`, and
# the package wires them in here when it loads (spreadmap/__init__.py), in that order; config
# imports no module above it (issue 65) and ``validate`` still refuses every section's problem.
SECTION_CHECKS: list = []
# the targets whose noise SD a fitted noise law sets: those with a counting law (mfr, pd)
NOISE_LAW_TARGETS = tuple(t.name for t in REGISTRY.values() if t.count_column)


class ConfigError(ValueError):
    """A bad configuration value: the message says which key, what value, what is allowed.

    A ValueError raised by ``validate`` and ``load``, its message one line.
    """


def _key_path(path) -> str:
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "(top level)"


def _describe(error: jsonschema.ValidationError) -> str:
    key = _key_path(error.absolute_path)
    allowed = {
        "enum": lambda s: f"one of {s['enum']}",
        "minimum": lambda s: f">= {s['minimum']}",
        "maximum": lambda s: f"<= {s['maximum']}",
        "exclusiveMinimum": lambda s: f"> {s['exclusiveMinimum']}",
        "exclusiveMaximum": lambda s: f"< {s['exclusiveMaximum']}",
        "type": lambda s: f"of type {s['type']}",
        "required": lambda s: f"present (required keys: {s['required']})",
        "minProperties": lambda s: f"a mapping with at least {s['minProperties']} entry",
        "anyOf": _any_of,
    }
    validator = error.validator
    if validator == "additionalProperties":
        extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
        known = sorted(error.schema.get("properties", {}))
        where = f"under '{key}'" if error.absolute_path else "at the top level"
        return f"unknown config key(s) {extra} {where}; allowed keys: {known}"
    if validator == "required":
        return f"config key '{key}': {error.message}"
    rule = allowed.get(validator, lambda s: f"valid per the schema rule '{validator}'")(error.schema)
    message = f"config key '{key}': value {error.instance!r} is not allowed; it must be {rule}"
    if validator == "type" and _yaml_float(error.instance):
        message += f" (YAML 1.1 reads {error.instance} as a string: write {_yaml_float(error.instance)})"
    return message


def _any_of(schema: dict) -> str:
    """The anyOf rule in words: at least one of some keys (the schema's only use of it), or as named."""
    options = schema["anyOf"]
    if all(set(option) == {"required"} for option in options):
        return f"a mapping with at least one of the keys {[key for option in options for key in option['required']]}"
    return "valid per the schema rule 'anyOf'"


def _yaml_float(value) -> str | None:
    """How to write a number that YAML 1.1 (PyYAML) read as a string because its exponent has no
    sign or its mantissa no dot (2.1e9 -> 2.1e+9, 1e-6 -> 1.0e-6); None for anything else."""
    if not isinstance(value, str) or "e" not in value.lower():
        return None
    try:
        float(value)
    except ValueError:
        return None
    mantissa, exponent = value.strip().lower().split("e")
    mantissa = mantissa if "." in mantissa else mantissa + ".0"
    exponent = exponent if exponent[:1] in "+-" else "+" + exponent
    return f"{mantissa}e{exponent}"


# config sections renamed so that the names say which is which: old name -> new name (the old one
# is still read, with a warning naming both)
RENAMED_SECTIONS = {"convergence": "study_rule"}
RENAME_REASONS = {"convergence": "the study's five-statistic rule; `converge:` stays the main job's loop"}


def renamed_sections(config: dict) -> dict:
    """Move the sections under an old name (``RENAMED_SECTIONS``) to their new name, in place,
    with a FutureWarning naming the old and the new key.

    Called by ``validate`` (so every config the workflow reads) and by readers of published
    configs that are not validated (``spreadlab.study.summary``).

    Parameters
    ----------
    config : dict
        A configuration as read from YAML; changed in place.

    Returns
    -------
    dict
        The same config, with the new names only.

    Raises
    ------
    ConfigError
        If a section is given under both its old and its new name.
    """
    for old, new in RENAMED_SECTIONS.items():
        if old not in config:
            continue
        if new in config:
            raise ConfigError(f"config has both '{old}:' and '{new}:'; '{old}:' is the old name of '{new}:' "
                              f"({RENAME_REASONS[old]}): keep '{new}:' only")
        warnings.warn(f"config key '{old}:' is deprecated, read as '{new}:' ({RENAME_REASONS[old]}); "
                      f"rename it to '{new}:'", FutureWarning, stacklevel=2)
        config[new] = config.pop(old)
    return config


# config keys renamed inside a section: (section, old key) -> (new key, what changed); the old key is
# read as the new one where the new one is not given, and ignored where it is (the new one takes
# precedence), with a warning naming both either way
RENAMED_KEYS = {("stability", "max_flow_decline_z"): (
    "max_flow_trend_z", "the bound now holds for a fall and a rise of the flow between the window's halves, "
                        "in SEs of its own within-window noise (flow_trend_z_batch), where it held for a fall "
                        "in counting-noise SEs")}


def renamed_keys(config: dict) -> dict:
    """Move the keys under an old name (``RENAMED_KEYS``) to their new name in their section, in
    place, with a FutureWarning naming both; where the new key is given too it takes precedence
    and the old one is dropped, with a FutureWarning saying so.

    Called by ``validate`` (so every config the workflow reads) and by readers handed a section
    that was not validated (``spreadmap.metrics.case.flow_trend_bound``).

    Parameters
    ----------
    config : dict
        A configuration as read from YAML; changed in place (its sections too).

    Returns
    -------
    dict
        The same config, with the new names only.
    """
    for (section, old), (new, why) in RENAMED_KEYS.items():
        part = config.get(section)
        if not isinstance(part, dict) or old not in part:
            continue
        value = part.pop(old)
        if new in part:
            warnings.warn(f"config key '{section}.{old}' is deprecated and ignored: '{section}.{new}' is given and "
                          f"takes precedence ({why}); remove '{section}.{old}'", FutureWarning, stacklevel=2)
        else:
            warnings.warn(f"config key '{section}.{old}' is deprecated, read as '{section}.{new}' = {value!r} ({why}); "
                          f"rename it to '{section}.{new}'", FutureWarning, stacklevel=2)
            part[new] = value
    return config


# where a config names targets: (section, key) holding a list of target names, a mapping keyed by
# them, or one name
TARGET_PLACES = (("noise_calibration", "targets"), ("fidelity_correction", "targets"),
                 ("converge", "map_error", "tolerance"), ("surrogate", "targets"), ("maps", "machine", "y"),
                 ("decisions", "bounds"), ("decisions", "quality", "target"))


def _target_places(config: dict):
    """(where, holder, key) of every value of `config` that names targets (``TARGET_PLACES``;
    each region of ``noise_calibration``)."""
    for place in TARGET_PLACES:
        holders = [(place[0], config.get(place[0]))]
        if place[0] == "noise_calibration":
            holders = [(f"noise_calibration[{i}]", region) for i, region in enumerate(holders[0][1] or [])]
        for where, holder in holders:
            for key in place[1:-1]:
                holder = holder.get(key) if isinstance(holder, dict) else None
                where += f".{key}"
            if isinstance(holder, dict) and place[-1] in holder:
                yield f"{where}.{place[-1]}", holder, place[-1]


def renamed_targets(config: dict) -> dict:
    """Read a target the config names by its old name (``spreadmap.targets.RENAMED``:
    ``layer_packing`` -> ``layer_fill``) as its new one, in place, with one FutureWarning naming
    where.

    Called by ``validate``, so published configs (docs/*/config.yaml) that list ``layer_packing``
    in ``noise_calibration`` targets keep validating.

    Parameters
    ----------
    config : dict
        A configuration as read from YAML: its lists of targets, its mappings keyed by them and
        its single target names (``TARGET_PLACES``) are rewritten in place.

    Returns
    -------
    dict
        `config` itself, every old target name in it replaced by the new one.

    Raises
    ------
    ConfigError
        If a mapping keyed by targets holds a target under both its old and its new name.
    """
    found = []
    for where, holder, key in _target_places(config):
        value = holder[key]
        if isinstance(value, str):
            if value in RENAMED_TARGETS:
                holder[key] = RENAMED_TARGETS[value]
                found.append(where)
        elif isinstance(value, list):
            if any(v in RENAMED_TARGETS for v in value if isinstance(v, str)):
                holder[key] = [RENAMED_TARGETS.get(v, v) if isinstance(v, str) else v for v in value]
                found.append(where)
        elif isinstance(value, dict):
            for old, new in RENAMED_TARGETS.items():
                if old not in value:
                    continue
                if new in value:
                    raise ConfigError(f"config key '{where}' has both '{old}' and '{new}'; '{old}' is the old name "
                                      f"of '{new}': keep '{new}' only")
                value = holder[key] = {(new if k == old else k): v for k, v in value.items()}  # in its order
                found.append(where)
    if found:
        names = ", ".join(f"'{old}' (now '{new}')" for old, new in RENAMED_TARGETS.items())
        warnings.warn(f"config names a target by its old name {names} in {', '.join(found)}: read under its new "
                      f"name; rename it there", FutureWarning, stacklevel=2)
    return config


def validate(config: dict, schema_path: Path | str = SCHEMA) -> dict:
    """Validate `config` in place with Snakemake's validator (defaults filled), then the cross-key rules.

    A section under its old name (``RENAMED_SECTIONS``: ``convergence`` -> ``study_rule``) is
    first moved to its new one, and a key under its old name (``RENAMED_KEYS``:
    ``stability.max_flow_decline_z`` -> ``stability.max_flow_trend_z``) to its new one unless
    that is given too, and a target under its old name (``renamed_targets``: ``layer_packing`` ->
    ``layer_fill``) to its new one, each with a warning. The schema (schemas/config.schema.yaml) fills every
    default it has; the cross-key rules are the
    checks a schema cannot express (the presets named exist, ranges with min below max, noise
    calibration regions that are not empty, the noise model's sections, the pictures' points, the
    surrogate, decisions and fidelity sections, the PD box against the blade).

    Parameters
    ----------
    config : dict
        The configuration as read from YAML; changed in place (defaults filled).
    schema_path : pathlib.Path or str, optional
        The JSON schema (YAML); default: schemas/config.schema.yaml (``SCHEMA``).

    Returns
    -------
    dict
        The same config, validated and with its defaults filled.

    Raises
    ------
    ConfigError
        With a one-line message naming the key, the bad value and what is allowed (or a section
        given under both its old and its new name).
    """
    from snakemake.exceptions import WorkflowError
    from snakemake.utils import validate as snakemake_validate

    renamed_sections(config)
    renamed_keys(config)
    renamed_targets(config)
    try:
        snakemake_validate(config, str(schema_path), set_default=True)
    except WorkflowError:
        schema = read_yaml(Path(schema_path).read_text())
        validator = jsonschema.Draft202012Validator(schema)
        error = jsonschema.exceptions.best_match(validator.iter_errors(config))
        raise ConfigError(_describe(error) if error else "config does not match its schema") from None
    _check_cross_keys(config)
    return config


def _check_cross_keys(config: dict) -> None:
    presets = config["presets"]
    if config["preset"] not in presets:
        raise ConfigError(f"config key 'preset': value {config['preset']!r} is not allowed; "
                          f"it must be one of the presets defined: {sorted(presets)}")
    preset_keys = [("points.preset", (config.get("points") or {}).get("preset"))]
    preset_keys += [(f"sweeps.{name}.preset", sweep.get("preset")) for name, sweep in (config.get("sweeps") or {}).items()]
    preset_keys += [(f"points.named.{name}.preset", point.get("preset"))
                    for name, point in ((config.get("points") or {}).get("named") or {}).items()]
    for key, value in preset_keys:
        if value is not None and value not in presets:
            raise ConfigError(f"config key '{key}': value {value!r} is not allowed; "
                              f"it must be one of the presets defined: {sorted(presets)}")
    for name, rng in (config.get("ranges") or {}).items():
        if not rng["min"] < rng["max"]:
            raise ConfigError(f"config key 'ranges.{name}': min {rng['min']} must be below max {rng['max']}")
    for i, region in enumerate(config.get("noise_calibration") or []):
        if region.get("h_over_d_from", 0.0) >= region.get("h_over_d_below", float("inf")):
            raise ConfigError(f"config key 'noise_calibration[{i}]': h_over_d_from {region['h_over_d_from']} "
                              f"must be below h_over_d_below {region['h_over_d_below']} (the region is empty)")
    if config.get("noise_model"):
        try:
            check_sections(config["noise_model"], config.get("noise_calibration"))
        except ValueError as error:
            raise ConfigError(f"config key 'noise_calibration': {error}") from None
    tails = config["material"]["size_distribution"]["tails"]
    if not tails[0] < 0.5 < tails[1]:
        raise ConfigError(f"config key 'material.size_distribution.tails': value {tails} is not allowed; "
                          f"it must be two volume quantiles [low, high] with low < 0.5 < high (e.g. [0.05, 0.95])")
    named = set(((config.get("points") or {}).get("named") or {}))
    for key in ("cases", "vtk"):
        for name in config["pictures"][key]:
            if name not in named:
                raise ConfigError(f"config key 'pictures.{key}': value {name!r} is not allowed; "
                                  f"it must name a chosen point of points.named: {sorted(named)}")
    clearance = config["metrics"]["pd_clearance_d"]  # filled from the schema by validate() above
    for name, preset in presets.items():
        if preset["window_d"] - clearance < config["scene"]["blade_thickness_d"]:
            raise ConfigError(f"config key 'presets.{name}.window_d': value {preset['window_d']} is not allowed; "
                              f"the PD box spans the window less the clearance behind the blade "
                              f"(metrics.pd_clearance_d = {clearance}) and must be at least the blade thickness "
                              f"(scene.blade_thickness_d = {config['scene']['blade_thickness_d']})")
    for check in SECTION_CHECKS:
        for problem in check(config):
            raise ConfigError(problem)


def check_sections(noise_model: dict | None, noise_calibration: list | None) -> None:
    """Refuse a band of `noise_calibration` that would scale a target the fitted law sets (a region
    without `targets` scales every target): the law supersedes the bands for MFR and PD.

    Parameters
    ----------
    noise_model : dict or None
        The config's `noise_model` section; None or empty: nothing to check.
    noise_calibration : list or None
        The config's `noise_calibration` regions.

    Raises
    ------
    ValueError
        If a region scales MFR or PD while `noise_model` sets that target's noise; the message
        names the region's index.
    """
    if not noise_model:
        return
    covered = [t for t in NOISE_LAW_TARGETS if t in noise_model]
    for i, region in enumerate(noise_calibration or []):
        named = region.get("targets") or list(target_names())
        clash = sorted(set(named) & set(covered))
        if clash:
            raise ValueError(f"noise_calibration[{i}] scales {clash}, whose noise SDs noise_model sets "
                             f"(a region without `targets` scales every target): name the layer measures it "
                             f"scales under `targets`, or remove it")


def load(path: Path | str) -> dict:
    """Read a YAML config file and validate it.

    Parameters
    ----------
    path : pathlib.Path or str
        The config file (e.g. config.yaml); an empty file is an empty config.

    Returns
    -------
    dict
        The validated config with the schema's defaults filled (``validate``).

    Raises
    ------
    OSError
        If the file cannot be read.
    yaml.YAMLError
        If the file is not YAML.
    ConfigError
        If the config is not valid (``validate``).
    """
    with open(path) as fh:
        config = read_yaml(fh.read()) or {}
    return validate(copy.deepcopy(config))
