"""Render the YADE scene template into one self-contained script per case: the template's
PARAMS block is replaced by the case's parameters, everything else is kept verbatim, so the
rendered file is readable and re-runnable by hand with `yade -n -x case.py`."""
from __future__ import annotations

import pprint
import re
from pathlib import Path

TEMPLATE = Path(__file__).resolve().parents[2] / "yade_scripts" / "spreading_case.py"
_BLOCK = re.compile(r"(# --- case parameters.*?---\n)PARAMS = \{.*?\n\}\n(# --- end of case parameters ---)", re.S)
# the PARAMS block of a rendered script (render: a pprint of the parameters before the end marker)
_RENDERED = re.compile(r"^PARAMS = (\{.*?\})\n# --- end of case parameters ---", re.S | re.M)


def template_sha256(template: Path | str = TEMPLATE) -> str:
    """Content hash of the scene template.

    Part of every case's parameters, so that a change of the scene re-renders and re-runs the cases
    (and invalidates finished simulations).

    Parameters
    ----------
    template : pathlib.Path or str, optional
        The scene template; default: the shipped yade_scripts/spreading_case.py (``TEMPLATE``).

    Returns
    -------
    str
        The first 16 hex digits of the SHA-256 of the template's bytes.
    """
    import hashlib

    return hashlib.sha256(Path(template).read_bytes()).hexdigest()[:16]


def render(params: dict, template: Path | str = TEMPLATE) -> str:
    """The YADE scene template with its PARAMS block replaced by one case's parameters.

    Everything else is kept verbatim, so the rendered script is readable and re-runnable by hand
    with ``yade -n -x case.py``; the block's header names the case, and the parameters are written
    in their own order (``pprint``, width 100), so that ``rendered_params`` reads them back.

    Parameters
    ----------
    params : dict
        The case's parameters (``spreadmap.case.identity.case_scene``), with ``case_id``.
    template : pathlib.Path or str, optional
        The scene template; default: the shipped yade_scripts/spreading_case.py (``TEMPLATE``).

    Returns
    -------
    str
        The rendered script's text.

    Raises
    ------
    ValueError
        If the parameters' ``scene_sha256`` (when present) is not the template's hash (the case was
        derived for another version of it), or the template has no PARAMS block between the
        case-parameter markers.
    """
    text = Path(template).read_text()
    if params.get("scene_sha256") not in (None, template_sha256(template)):
        raise ValueError(f"case {params['case_id']} was derived for another version of {template}")
    if not _BLOCK.search(text):
        raise ValueError(f"{template}: no PARAMS block between the case-parameter markers")
    block = "PARAMS = " + pprint.pformat(params, sort_dicts=False, width=100) + "\n"
    header = f"# --- case parameters of {params['case_id']} (rendered by spreadmap) ---\n"
    return _BLOCK.sub(lambda m: header + block + m.group(2), text, count=1)


def rendered_params(text: str) -> dict:
    """The parameters a script rendered by `render` carries (its PARAMS block read back).

    Parameters
    ----------
    text : str
        The rendered script's text.

    Returns
    -------
    dict
        The PARAMS block's literal dict.

    Raises
    ------
    ValueError
        When there is no such block, or it is not a literal dict.
    """
    import ast

    match = _RENDERED.search(text)
    if not match:
        raise ValueError("no PARAMS block")
    try:
        params = ast.literal_eval(match.group(1))
    except (ValueError, SyntaxError):
        raise ValueError("the PARAMS block is not a literal") from None
    if not isinstance(params, dict):
        raise ValueError("PARAMS is not a dict")
    return params
