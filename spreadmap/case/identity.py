"""Case identity. A case is its content: every parameter the YADE scene script receives (the design
point at the precision simulated, the preset's values, the material, the scene settings, the packing
seed and the hash of the scene template). Two requests for the same content are the same case, run
once; two contents are two cases, side by side in results/cases/, never one overwriting the other.

A case id is readable first, then keyed: `<preset>-f<f>-d<d>-h<h>-v<v>-s<seed>-<key>`, the key
being 8 hex digits of the SHA-256 of the case's parameters without the fields that only name it
(content_key). Ids before issue 35 were the readable part alone (LEGACY_CASE_ID_PATTERN): they did
not say which material or scene a case was run with.
"""
from __future__ import annotations

import hashlib
import json
import re

# Precision at which a design point is simulated (and named).
DECIMALS = {"f": 4, "d_um": 3, "h_um": 3, "v_mm_s": 4}
KEY_HEX = 8
READABLE_PATTERN = r"[a-z][a-z0-9_]*-f\d+\.\d{4}-d\d+\.\d{3}-h\d+\.\d{3}-v\d+\.\d{4}-s\d+"
CASE_ID_PATTERN = READABLE_PATTERN + rf"-[0-9a-f]{{{KEY_HEX}}}"
LEGACY_CASE_ID_PATTERN = READABLE_PATTERN  # a case id before content keys (issue 35)
# Fields of a case's parameters that name it and do not change what is simulated.
NAMING_FIELDS = ("case_id",)
# Significant digits of a float in the key: a value computed on another machine may differ in its
# last bit (a libm's pow or exp), which must not make the same case another one.
KEY_DIGITS = 12


def rounded(point: dict) -> dict:
    """The design point as simulated: each parameter rounded to DECIMALS."""
    return {k: round(float(point[k]), n) for k, n in DECIMALS.items()}


def readable_id(point: dict, preset: str, seed: int) -> str:
    """The readable part of a case id: preset, design point (rounded as simulated) and packing seed.
    Alone, it was the case id before content keys (issue 35)."""
    p = rounded(point)
    return f"{preset}-f{p['f']:.4f}-d{p['d_um']:.3f}-h{p['h_um']:.3f}-v{p['v_mm_s']:.4f}-s{int(seed)}"


def readable_part(cid: str) -> str:
    """The readable part of a case id (a legacy id is all readable part)."""
    return re.sub(rf"-[0-9a-f]{{{KEY_HEX}}}$", "", cid) if re.fullmatch(CASE_ID_PATTERN, cid) else cid


def is_legacy_id(cid: str) -> bool:
    """Whether a case id is of the form before content keys (issue 35)."""
    return re.fullmatch(LEGACY_CASE_ID_PATTERN, str(cid)) is not None


def _canonical(value):
    """A parameter value as it enters the key: a number as the text of its value to KEY_DIGITS
    significant digits, the same for an int and a float of one value (a config's `7980` and
    `7980.0` are one material; an int too long for that, exactly); containers recursively; bools,
    strings and None as they are."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int) and abs(value) >= 10 ** KEY_DIGITS:
        return str(value)
    if isinstance(value, (int, float)):
        return format(float(value), f".{KEY_DIGITS}g")
    if isinstance(value, dict):
        return {str(k): _canonical(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    if hasattr(value, "item"):  # a numpy scalar
        return _canonical(value.item())
    raise TypeError(f"a case parameter of type {type(value).__name__} cannot enter a case's key: {value!r}")


def content_key(params: dict) -> str:
    """The key of a case's content: the first KEY_HEX hex digits of the SHA-256 of its parameters
    (what the YADE script receives, scene_sha256 included) without the fields that only name it,
    as canonical JSON (sorted keys, floats at KEY_DIGITS significant digits)."""
    content = {k: v for k, v in params.items() if k not in NAMING_FIELDS}
    text = json.dumps(_canonical(content), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_HEX]


def keyed_id(params: dict) -> str:
    """The case id of a case's parameters: the readable part from its point, preset and seed, then
    its content key."""
    return f"{readable_id(params['point'], params['preset'], params['seed'])}-{content_key(params)}"


def repeat_group(params: dict) -> str:
    """What the seed repeats of a case share: its readable id without the seed, then the content
    key of its parameters with the seed left out (two materials' repeats at one point are two groups)."""
    readable = re.sub(r"-s\d+$", "", readable_id(params["point"], params["preset"], params["seed"]))
    return f"{readable}-{content_key({**params, 'seed': None})}"


def case_scene(point: dict, preset: str, config: dict, seed: int | None = None,
               scene_sha256: str | None = None) -> tuple[str, dict]:
    """(case id, the parameters of the YADE scene script) of a design point at a preset and packing
    seed (default: the scene's) under a configuration; scene_sha256 is the template's hash
    (default: spreadmap.case.render.template_sha256() of the shipped template). Raises
    spreadmap.case.scene.UnsafeTimeStep or ValueError for a case that must not run."""
    from .render import template_sha256
    from .scene import scene_parameters

    seed = config["scene"]["seed"] if seed is None else seed
    params = scene_parameters(rounded(point), preset, config, readable_id(point, preset, seed), seed)
    params["scene_sha256"] = template_sha256() if scene_sha256 is None else scene_sha256
    cid = keyed_id(params)
    params["case_id"] = cid
    return cid, params


def case_id(point: dict, preset: str, config: dict, seed: int | None = None, scene_sha256: str | None = None) -> str:
    """The case id of a design point at a preset and packing seed under a configuration (case_scene)."""
    return case_scene(point, preset, config, seed, scene_sha256)[0]
