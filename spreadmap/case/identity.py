"""Case identity. A case is what it simulates: every parameter the YADE scene script receives that
reaches the simulation (the design point at the precision simulated, the preset's values, the
material, the scene settings, the packing seed) and the scene template's code
(spreadmap.case.render.template_sha256). Two requests for the same content are the same case, run
once; two contents are two cases, side by side in results/cases/, never one overwriting the other.

A case id is readable first, then keyed: `<preset>-f<f>-d<d>-h<h>-v<v>-s<seed>-<key>`, the key
being 8 hex digits of the SHA-256 of the case's parameters without the fields that only name it or
only keep its books (NOT_KEYED: its id, the outer timeout, the progress cadence, the step estimate;
content_key). Ids before issue 35 were the readable part alone (LEGACY_CASE_ID_PATTERN): they did
not say which material or scene a case was run with. Ids from issue 35 to issue 65 keyed every
parameter but the id, and the template's bytes (a comment's fix re-keyed every case): the tables
published then keep them; spreadmap.case.migrate carries such case folders to today's ids.
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
# Fields that keep a case's books and do not change what is simulated either: the launcher's outer
# timeout, the cadence of the log's progress lines, the step estimate they print (issue 65).
BOOKKEEPING_FIELDS = ("timeout_s", "progress_every_s", "estimated_steps")
NOT_KEYED = NAMING_FIELDS + BOOKKEEPING_FIELDS


class SceneParams:
    """A case's scene parameters as its rules hand them to their scripts (``.params``), out of sight
    of Snakemake's params re-run trigger, which records only builtin types: the case's id (its
    folder) already holds everything the case simulates, so a changed ``timeout_s`` or progress
    cadence, which the id leaves out, re-renders and re-runs no finished case."""

    __slots__ = ("params",)

    def __init__(self, params: dict):
        self.params = params
# Significant digits of a float in the key: a value computed on another machine may differ in its
# last bit (a libm's pow or exp), which must not make the same case another one.
KEY_DIGITS = 12


def rounded(point: dict) -> dict:
    """The design point as simulated: each parameter rounded to DECIMALS.

    Parameters
    ----------
    point : dict
        The design point: ``f`` [-], ``d_um`` [um], ``h_um`` [um], ``v_mm_s`` [mm/s] (other keys
        are ignored).

    Returns
    -------
    dict
        ``{"f", "d_um", "h_um", "v_mm_s"}`` as floats, rounded to ``DECIMALS`` (4, 3, 3 and 4
        decimals).

    Raises
    ------
    KeyError
        If the point lacks one of the four parameters.
    """
    return {k: round(float(point[k]), n) for k, n in DECIMALS.items()}


def readable_id(point: dict, preset: str, seed: int) -> str:
    """The readable part of a case id: preset, design point (rounded as simulated) and packing seed.

    Alone, it was the case id before content keys (issue 35).

    Parameters
    ----------
    point : dict
        The design point: ``f`` [-], ``d_um`` [um], ``h_um`` [um], ``v_mm_s`` [mm/s]; rounded as
        simulated (``rounded``).
    preset : str
        The fidelity preset's name.
    seed : int
        The packing seed.

    Returns
    -------
    str
        ``<preset>-f<f>-d<d>-h<h>-v<v>-s<seed>``, f and v with 4 decimals, d and h with 3
        (``READABLE_PATTERN``).
    """
    p = rounded(point)
    return f"{preset}-f{p['f']:.4f}-d{p['d_um']:.3f}-h{p['h_um']:.3f}-v{p['v_mm_s']:.4f}-s{int(seed)}"


def readable_part(cid: str) -> str:
    """The readable part of a case id (a legacy id is all readable part).

    Parameters
    ----------
    cid : str
        A case id: a content id (``CASE_ID_PATTERN``) or a legacy one.

    Returns
    -------
    str
        The id without its trailing ``-<key>`` (``KEY_HEX`` hex digits) when it is a content id;
        anything else unchanged.
    """
    return re.sub(rf"-[0-9a-f]{{{KEY_HEX}}}$", "", cid) if re.fullmatch(CASE_ID_PATTERN, cid) else cid


def is_legacy_id(cid: str) -> bool:
    """Whether a case id is of the form before content keys (issue 35).

    Parameters
    ----------
    cid : str
        A case id (anything else is read as its ``str``).

    Returns
    -------
    bool
        True when the whole id matches ``LEGACY_CASE_ID_PATTERN`` (the readable part, no key).
    """
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


def content_key(params: dict, left_out: tuple[str, ...] = NOT_KEYED) -> str:
    """The key of a case's content: the first KEY_HEX hex digits of the SHA-256 of its parameters.

    The parameters are what the YADE script receives (scene_sha256, the template's code hash,
    included) without the fields that only name it or keep its books (``NOT_KEYED``), as canonical
    JSON (sorted keys, floats at KEY_DIGITS significant digits; an int and a float of one value give
    one key).

    Parameters
    ----------
    params : dict
        The case's parameters (``case_scene``; ``case_id`` may be there or not).
    left_out : tuple of str, optional
        The fields left out; default ``NOT_KEYED``. ``NAMING_FIELDS`` gives the key of issue 35 to
        issue 65 (every parameter but the id), which spreadmap.case.migrate reads old folders by.

    Returns
    -------
    str
        ``KEY_HEX`` (8) lowercase hex digits.

    Raises
    ------
    TypeError
        If a parameter value cannot enter a key (not a number, bool, str, None, dict, list, tuple
        or numpy scalar).
    """
    content = {k: v for k, v in params.items() if k not in left_out}
    text = json.dumps(_canonical(content), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_HEX]


def keyed_id(params: dict, left_out: tuple[str, ...] = NOT_KEYED) -> str:
    """The case id of a case's parameters: the readable part from its point, preset and seed, then its content key.

    Parameters
    ----------
    params : dict
        The case's parameters (``case_scene``): ``point`` (f [-], d_um [um], h_um [um],
        v_mm_s [mm/s]), ``preset`` and ``seed`` name it; all of them but ``left_out`` key it.
    left_out : tuple of str, optional
        The fields the key leaves out (``content_key``); default ``NOT_KEYED``.

    Returns
    -------
    str
        ``<readable part>-<content key>`` (``CASE_ID_PATTERN``).

    Raises
    ------
    KeyError
        If the parameters lack ``point``, ``preset`` or ``seed``.
    TypeError
        If a parameter cannot enter the key (``content_key``).
    """
    return f"{readable_id(params['point'], params['preset'], params['seed'])}-{content_key(params, left_out)}"


def repeat_group(params: dict) -> str:
    """What the seed repeats of a case share: its readable id without the seed, then a content key without the seed.

    The key is that of its parameters with the seed left out, so two materials' repeats at one point
    are two groups.

    Parameters
    ----------
    params : dict
        The case's parameters (``case_scene``): ``point``, ``preset`` and ``seed`` at least.

    Returns
    -------
    str
        ``<preset>-f<f>-d<d>-h<h>-v<v>-<key of the parameters with seed None>``.

    Raises
    ------
    KeyError
        If the parameters lack ``point``, ``preset`` or ``seed``.
    TypeError
        If a parameter cannot enter the key (``content_key``).
    """
    readable = re.sub(r"-s\d+$", "", readable_id(params["point"], params["preset"], params["seed"]))
    return f"{readable}-{content_key({**params, 'seed': None})}"


def case_scene(point: dict, preset: str, config: dict, seed: int | None = None,
               scene_sha256: str | None = None) -> tuple[str, dict]:
    """(case id, the parameters of the YADE scene script) of a design point at a preset and packing seed under a config.

    The point is rounded as simulated (``rounded``); the parameters are
    ``spreadmap.case.scene.scene_parameters``' with ``scene_sha256`` and then ``case_id`` added.

    Parameters
    ----------
    point : dict
        The design point: ``f`` [-], ``d_um`` [um], ``h_um`` [um], ``v_mm_s`` [mm/s].
    preset : str
        The preset's name (a key of the config's ``presets``).
    config : dict
        The loaded configuration (``spreadmap.config.load``): presets, material, scene, metrics.
    seed : int or None, optional
        The packing seed; None: the scene's (config ``scene.seed``).
    scene_sha256 : str or None, optional
        The hash of the scene template's code; None: ``spreadmap.case.render.template_sha256()`` of
        the shipped template.

    Returns
    -------
    case_id : str
        The case id, ``<readable part>-<content key>``.
    params : dict
        The parameters of the YADE scene script (SI units), with ``scene_sha256`` and ``case_id``.

    Raises
    ------
    spreadmap.case.scene.UnsafeTimeStep
        For a case that must not run: the preset forces a time step above its critical step.
    ValueError
        For a case that must not run: a parameter of the point is not a positive number.
    """
    from .render import template_sha256
    from .scene import scene_parameters

    seed = config["scene"]["seed"] if seed is None else seed
    params = scene_parameters(rounded(point), preset, config, readable_id(point, preset, seed), seed)
    params["scene_sha256"] = template_sha256() if scene_sha256 is None else scene_sha256
    cid = keyed_id(params)
    params["case_id"] = cid
    return cid, params


def case_id(point: dict, preset: str, config: dict, seed: int | None = None, scene_sha256: str | None = None) -> str:
    """The case id of a design point at a preset and packing seed under a configuration (case_scene).

    Parameters
    ----------
    point : dict
        The design point: ``f`` [-], ``d_um`` [um], ``h_um`` [um], ``v_mm_s`` [mm/s].
    preset : str
        The preset's name (a key of the config's ``presets``).
    config : dict
        The loaded configuration (``spreadmap.config.load``).
    seed : int or None, optional
        The packing seed; None: the scene's (config ``scene.seed``).
    scene_sha256 : str or None, optional
        The hash of the scene template's code; None: that of the shipped template.

    Returns
    -------
    str
        The case id, ``<readable part>-<content key>``.

    Raises
    ------
    spreadmap.case.scene.UnsafeTimeStep
        For a case that must not run (``case_scene``).
    ValueError
        For a case that must not run (``case_scene``).
    """
    return case_scene(point, preset, config, seed, scene_sha256)[0]
