"""The command line (``tools/predict.py``) and the Snakemake entry (``scripts/predict.py``) around
``prediction.predict``."""
from __future__ import annotations

import argparse
import io
import math
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from ..design import NAMES
from ..files import atomic_path
from .prediction import OutOfRangeWarning, as_points, predict
from .saved_model import ModelFileError, load_model


def parse_point(tokens: Sequence[str]) -> dict:
    """``["f=0.3", "d_um=30", ...]`` -> {"f": 0.3, ...}; every parameter exactly once."""
    point = {}
    for tok in tokens:
        if "=" not in tok:
            raise ValueError(f"point token {tok!r} is not NAME=VALUE (names: {', '.join(NAMES)})")
        name, _, val = tok.partition("=")
        name = name.strip()
        if name not in NAMES:
            raise ValueError(f"unknown parameter {name!r} in {tok!r}; expected {', '.join(NAMES)}")
        if name in point:
            raise ValueError(f"parameter {name!r} given twice in one point")
        try:
            x = float(val)
        except ValueError:
            raise ValueError(f"value of {name!r} is not a number: {val!r}") from None
        if not math.isfinite(x):
            raise ValueError(f"value of {name!r} is not finite: {val!r}")
        point[name] = x
    missing = [n for n in NAMES if n not in point]
    if missing:
        raise ValueError(f"point {' '.join(tokens)!r} lacks parameter(s) {missing}")
    return point


def read_points_csv(path) -> pd.DataFrame:
    """Points from a CSV: the columns f, d_um, h_um, v_mm_s, optionally name, preset, seed."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"points file not found: {path}")
    try:
        return pd.read_csv(path, comment="#", skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
        raise ValueError(f"cannot read points CSV {path}: {e}") from None


def predict_logged(model, points, log) -> pd.DataFrame:
    """predict(), every OutOfRangeWarning also written as 'warning: ...' to ``log``.

    Other warnings are re-issued as they came.

    Parameters
    ----------
    model : SurrogateModel
        The saved surrogate (``load_model``).
    points : pandas.DataFrame or Mapping or array_like
        The points in physical units (``prediction.as_points``: columns f, d_um, h_um, v_mm_s,
        optionally name, preset, seed; or an (n, 4) array in that order).
    log : file-like
        Where the 'warning: ...' lines are printed (``print(..., file=log)``).

    Returns
    -------
    pandas.DataFrame
        ``prediction.predict``'s table: per point the inputs, per target the mean, ``<t>_model_sd``
        and ``<t>_run_sd``, then ``data_distance``, ``outside_design``, ``gap_below_d`` and
        ``supported``.

    Raises
    ------
    TypeError
        If `model` is not a SurrogateModel.
    ValueError
        If the points are malformed (``prediction.as_points``).
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", OutOfRangeWarning)
        out = predict(model, points)
    for w in caught:
        if issubclass(w.category, OutOfRangeWarning):
            print(f"warning: {w.message}", file=log)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return out


def write_csv(out: pd.DataFrame, path) -> None:
    """Write a table as CSV (no index column), atomically (``spreadmap.files.atomic_path``).

    Parameters
    ----------
    out : pandas.DataFrame
        The table (e.g. ``predict_logged``'s predictions).
    path : pathlib.Path or str
        The CSV file; replaced whole or not at all (its folder is made if missing).

    Raises
    ------
    OSError
        If the file cannot be written; a full disk or a file-size limit names `path`.
    """
    with atomic_path(path) as tmp:
        out.to_csv(tmp, index=False)


def cli_main(argv: Sequence[str] | None = None) -> int:
    """The command line of scripts/predict.py: predict with a saved surrogate at given points.

    ``predict.py MODEL [--point NAME=VALUE ...]... [--csv FILE] [--out FILE]``: per target the
    mean, the model's SD and the SD a new DEM run would show, printed as a table (and written to
    ``--out`` as CSV). Out-of-range warnings go to stderr.

    Parameters
    ----------
    argv : sequence of str or None, optional
        The arguments after the program name; None: ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status: 0 on success, 2 when the points or the model file are refused (the
        reason is printed to stderr as one line). argparse itself exits (status 2) on a bad
        command line.
    """
    ap = argparse.ArgumentParser(
        prog="predict.py",
        description="Predict with a saved spreadmap surrogate: per target the mean, the model's SD and "
                    "the SD a new DEM run would show.")
    ap.add_argument("model", help="model file written by the workflow (results/surrogate/model.joblib)")
    ap.add_argument("--point", nargs="+", action="append", default=[], metavar="NAME=VALUE",
                    help=f"one point: {' '.join(n + '=...' for n in NAMES)} (repeatable)")
    ap.add_argument("--csv", help=f"CSV of points: {', '.join(NAMES)} (and optionally name, preset, seed)")
    ap.add_argument("--out", help="write the predictions to this CSV (the table is printed as well)")
    args = ap.parse_args(argv)
    try:
        if not args.point and not args.csv:
            raise ValueError("no points given: use --point NAME=VALUE ... and/or --csv FILE")
        frames = []
        if args.point:
            frames.append(pd.DataFrame([parse_point(tokens) for tokens in args.point]))
        if args.csv:
            frames.append(read_points_csv(args.csv))
        pts = pd.concat(frames, ignore_index=True) if len(frames) > 1 else frames[0]
        as_points(pts)  # refuse malformed input before loading the model
        model = load_model(args.model)
        out = predict_logged(model, pts, sys.stderr)
    except (ValueError, ModelFileError) as e:
        print(f"predict.py: error: {e}", file=sys.stderr)
        return 2
    if args.out:
        write_csv(out, args.out)
    with pd.option_context("display.max_rows", None, "display.max_columns", None, "display.width", 250):
        print(out.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    return 0


def snakemake_main(smk) -> None:
    """Snakemake ``script:`` entry. input: ``model``, optional ``points`` (CSV); params: optional
    ``points`` (a list of {name: value} dicts or "NAME=VALUE ..." strings); output[0]: the CSV.

    Out-of-range warnings go to stderr and, if the rule declares one, to its log file.

    Parameters
    ----------
    smk : snakemake.script.Snakemake
        The rule script's ``snakemake`` object (``input``, ``params``, ``output``, ``log``).

    Raises
    ------
    ValueError
        If no points are given or they are malformed.
    ModelFileError
        If the model file is not a usable surrogate (``load_model``).
    """
    inp, params = smk.input, smk.params
    model_path = inp.model if hasattr(inp, "model") else inp[0]
    pts_csv = inp.points if hasattr(inp, "points") else (inp[1] if len(inp) > 1 else None)
    frames = []
    if pts_csv:
        frames.append(read_points_csv(pts_csv))
    p = getattr(params, "points", None)
    if p:
        frames.append(pd.DataFrame([parse_point(x.split()) if isinstance(x, str) else dict(x) for x in p]))
    if not frames:
        raise ValueError("no points: give input 'points' (CSV) or params 'points'")
    pts = pd.concat(frames, ignore_index=True)
    buf = io.StringIO()
    out = predict_logged(load_model(model_path), pts, buf)
    sys.stderr.write(buf.getvalue())
    if len(smk.log):
        Path(smk.log[0]).write_text(buf.getvalue())
    write_csv(out, smk.output[0])
