"""Render the YADE scene template into one self-contained script per case: the template's
PARAMS block is replaced by the case's parameters, everything else is kept verbatim, so the
rendered file is readable and re-runnable by hand with `yade -n -x case.py`."""
from __future__ import annotations

import ast
import pprint
import re
from pathlib import Path

TEMPLATE = Path(__file__).resolve().parents[2] / "yade_scripts" / "spreading_case.py"
_BLOCK = re.compile(r"(# --- case parameters.*?---\n)PARAMS = \{.*?\n\}\n(# --- end of case parameters ---)", re.S)
# the PARAMS block of a rendered script (render: a pprint of the parameters before the end marker)
_RENDERED = re.compile(r"^PARAMS = (\{.*?\})\n# --- end of case parameters ---", re.S | re.M)


def _without_docstrings(tree: ast.AST) -> ast.AST:
    """The tree with the docstring of the module and of every function and class left out (a body
    that was only its docstring gets `pass`)."""
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            first = node.body[0] if node.body else None
            if (isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
                    and isinstance(first.value.value, str)):
                node.body = node.body[1:] or [ast.Pass()]
    return tree


def _without_params_values(tree: ast.Module) -> ast.Module:
    """The tree with the module's `PARAMS = {...}` literal emptied: its values are a demo case's,
    replaced by each case's own when rendered (and keyed as the case's parameters)."""
    for node in tree.body:
        if (isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)
                and node.targets[0].id == "PARAMS"):
            node.value = ast.Dict(keys=[], values=[])
    return tree


def _dump(node) -> str:
    """A canonical text of an AST: each node's class and its fields in their order, the fields that
    are None or empty and the ones newer Pythons add with nothing in them (type_comment, kind,
    type_params) left out, so that one code dumps the same under Python 3.9-3.13."""
    if isinstance(node, ast.AST):
        fields = [f"{name}={_dump(value)}" for name, value in ast.iter_fields(node)
                  if name not in ("type_comment", "kind", "type_params") and value is not None and value != []]
        return f"{type(node).__name__}({','.join(fields)})"
    if isinstance(node, list):
        return "[" + ",".join(_dump(v) for v in node) + "]"
    return repr(node)


def template_code(text: str) -> str:
    """The scene template as code: what its parsed text does, without its comments (the parser drops
    them), its docstrings and the demo values of its PARAMS block.

    Parameters
    ----------
    text : str
        The template's text (Python).

    Returns
    -------
    str
        A canonical dump of its syntax tree (``_dump``): one text for one code, whatever its comments,
        docstrings, layout or demo parameters.

    Raises
    ------
    SyntaxError
        If the text is not Python.
    """
    return _dump(_without_params_values(_without_docstrings(ast.parse(text))))


def template_sha256(template: Path | str = TEMPLATE) -> str:
    """Hash of the scene template's code (``template_code``): part of every case's parameters, so that
    a change of what the scene does re-keys (re-renders and re-runs) every case, and a change of its
    comments, docstrings or demo PARAMS does not.

    (Before issue 65 it hashed the template's bytes: a comment's fix re-keyed every case;
    spreadmap.case.migrate.BYTE_HASHED_TEMPLATES carries the cases of those hashes.)

    Parameters
    ----------
    template : pathlib.Path or str, optional
        The scene template; default: the shipped yade_scripts/spreading_case.py (``TEMPLATE``).

    Returns
    -------
    str
        The first 16 hex digits of the SHA-256 of the template's code.
    """
    import hashlib

    return hashlib.sha256(template_code(Path(template).read_text()).encode()).hexdigest()[:16]


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
