"""Sample tables of the design space.

LDS: scrambled Halton in 4-D (scipy.stats.qmc.Halton), seeded. Points are generated in sequence,
so case i is the same point whatever the total N: LDS-N is a prefix of LDS-2N and growing a
sweep only adds cases. Lattice: k points per dimension, end points included, k^4 cases.
"""
from __future__ import annotations

import io
import itertools
import math
import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import qmc

from . import design
from .design import Design, to_physical


def halton_unit(n: int, seed: int) -> np.ndarray:
    """The first n points of the seeded scrambled Halton sequence in [0, 1)^4."""
    return qmc.Halton(d=len(design.NAMES), scramble=True, seed=seed).random(n)


def lattice_unit(k: int) -> np.ndarray:
    """k^4 points: every combination of k equally spaced values per dimension, ends included."""
    if k < 2:
        raise ValueError(f"a lattice needs k >= 2 points per dimension (k = {k})")
    axis = np.linspace(0.0, 1.0, k)
    return np.array(list(itertools.product(axis, repeat=len(design.NAMES))))


def _table(unit: np.ndarray, ranges: Design | Mapping | None) -> pd.DataFrame:
    table = pd.DataFrame(to_physical(unit, ranges), columns=list(design.NAMES))
    table.insert(0, "index", np.arange(len(table)))
    return table


def halton(n: int, seed: int, ranges: Design | Mapping | None = None) -> pd.DataFrame:
    """LDS sample table: columns index, f, d_um, h_um, v_mm_s.

    The first `n` points of the seeded scrambled Halton sequence (``halton_unit``), so the table
    for n is a prefix of the table for 2n.

    Parameters
    ----------
    n : int
        Number of points (rows).
    seed : int
        Seed of the scrambling (``scipy.stats.qmc.Halton``).
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.

    Returns
    -------
    pandas.DataFrame
        `n` rows: ``index`` (0 .. n-1, the position in the sequence) then the four parameters
        in physical units.
    """
    return _table(halton_unit(n, seed), ranges)


def lattice(k: int, ranges: Design | Mapping | None = None) -> pd.DataFrame:
    """Uniform lattice sample table with k points per dimension (k^4 rows).

    Parameters
    ----------
    k : int
        Points per dimension, end points included (k >= 2).
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.

    Returns
    -------
    pandas.DataFrame
        k^4 rows: ``index`` then the four parameters in physical units.

    Raises
    ------
    ValueError
        If ``k < 2``.
    """
    return _table(lattice_unit(k), ranges)


def chosen_points(points_config: dict | None, base_dir=".", presets=None) -> list[dict]:
    """The user's chosen points: config `points.named` then the rows of `points.csv`.
    Each entry: {"name", "point": {f, d_um, h_um, v_mm_s}, "preset" or None, "seed" or None}.
    The CSV is checked as `read_points_csv` says; `presets` (the config's presets), when given,
    are the preset names a row may name."""
    points_config = points_config or {}
    out = []
    for name, entry in (points_config.get("named") or {}).items():
        problem = point_name_problem(str(name))
        if problem:
            raise ValueError(f"config key 'points.named': {problem}")
        out.append({"name": str(name), "point": {k: float(entry[k]) for k in design.NAMES},
                    "preset": entry.get("preset"), "seed": entry.get("seed")})
    csv = points_config.get("csv")
    if csv:
        path = Path(base_dir) / csv
        if not path.exists():
            raise ValueError(f"config key 'points.csv': file {str(path)!r} does not exist")
        out += read_points_csv(path, taken={p["name"] for p in out}, presets=presets)
    return out


# A point's name is part of file paths (results/pictures/<name>.png, results/vtk/<name>/) and a
# wildcard of the rules that make them: no separator, no parent folder, not empty.
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")
# a preset's name starts every case id (spreadmap.case.identity.CASE_ID_PATTERN)
_PRESET = re.compile(r"[a-z][a-z0-9_]*")


def point_name_problem(name: str) -> str | None:
    """Why `name` cannot name a chosen point, or None."""
    if not name.strip():
        return "an empty name (a point's name is part of file paths: results/pictures/<name>.png)"
    if "/" in name or "\\" in name or ".." in name or name.startswith("."):
        return (f"name {name!r} is a path (it names files: results/pictures/<name>.png); "
                "a name may not contain '/', '\\' or '..' nor start with '.'")
    if _CONTROL.search(name) or name != name.strip():
        return f"name {name!r} has a control character or leading/trailing spaces"
    return None


def read_points_csv(path, taken=(), presets=None) -> list[dict]:
    """The rows of a points CSV (columns f, d_um, h_um, v_mm_s; optional name, preset, seed; other
    columns are ignored), each checked before anything is planned. Refused, naming the row (its
    line in the file, the header being row 1) and the column: a row with fields missing or extra,
    an empty or non-numeric or non-positive parameter, a seed that is not an integer >= 0, a name
    that is empty or a path or that is in `taken` (the config's named points), a name given to two
    points (or presets), the same name and seed twice (a name may repeat with other seeds at the
    same point and preset: the held-out check's seed repeats), a preset not in `presets`. Without
    a name column a row is named <file stem>_<i>."""
    import csv

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as error:
        raise ValueError(f"points CSV {path}: not UTF-8 text ({error})") from None
    records = []  # (line number of the record's first line, fields); blank lines skipped
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    line = 1
    try:
        for fields in reader:
            if fields and any(f.strip() for f in fields):
                records.append((line, fields))
            line = reader.line_num + 1
    except csv.Error as error:
        raise ValueError(f"points CSV {path}, row {line}: not CSV ({error})") from None
    if not records:
        raise ValueError(f"points CSV {path}: empty (no header row)")
    header_line, header = records[0]
    header = [c.strip() for c in header]
    seen_columns = {}
    for j, column in enumerate(header):
        if not column:
            raise ValueError(f"points CSV {path}, row {header_line}, column {j + 1}: empty column name")
        if column in seen_columns:
            raise ValueError(f"points CSV {path}, row {header_line}, column {column!r}: given twice "
                             f"(columns {seen_columns[column] + 1} and {j + 1})")
        seen_columns[column] = j
    missing = [c for c in design.NAMES if c not in header]
    if missing:
        raise ValueError(f"points CSV {path}: missing column(s) {missing}; required: {list(design.NAMES)}")

    def refuse(row: int, column: str, problem: str):
        raise ValueError(f"points CSV {path}, row {row}, column {column!r}: {problem}")

    out, by_name = [], {}
    for i, (row, fields) in enumerate(records[1:]):
        if len(fields) < len(header):
            refuse(row, header[len(fields)], f"missing value (the row has {len(fields)} fields, the header "
                                             f"{len(header)})")
        if len(fields) > len(header):
            raise ValueError(f"points CSV {path}, row {row}, column {len(header) + 1} (no name in the header): "
                             f"the row has {len(fields)} fields, the header {len(header)}")
        cell = {c: fields[j].strip() for c, j in seen_columns.items()}
        point = {}
        for k in design.NAMES:
            if not cell[k]:
                refuse(row, k, "missing value")
            try:
                value = float(cell[k])
            except ValueError:
                refuse(row, k, f"{cell[k]!r} is not a number")
            if not (math.isfinite(value) and value > 0):
                refuse(row, k, f"{cell[k]!r} is not a positive number")
            point[k] = value
        preset = cell.get("preset") or None
        if preset is not None and (not _PRESET.fullmatch(preset) or (presets is not None and preset not in presets)):
            known = f" (the config's presets: {', '.join(sorted(presets))})" if presets is not None else ""
            refuse(row, "preset", f"{preset!r} is not a preset{known}")
        seed = None
        if cell.get("seed"):
            try:
                value = float(cell["seed"])
            except ValueError:
                value = math.nan
            if not (math.isfinite(value) and value >= 0 and value.is_integer()):
                refuse(row, "seed", f"seed = {cell['seed']!r} is not allowed; a packing seed is an integer >= 0 "
                                    "(YADE seeds a negative one from the clock)")
            seed = int(value)
        if "name" in cell:
            name = fields[seen_columns["name"]]
            problem = point_name_problem(name)
            if problem:
                refuse(row, "name", problem)
            if name in taken:
                refuse(row, "name", f"{name!r} is also the name of a point in the config's points.named")
            first = by_name.setdefault(name, {"row": row, "point": point, "preset": preset, "seeds": {}})
            if first["point"] != point or first["preset"] != preset:
                refuse(row, "name", f"{name!r} names another point or preset on row {first['row']}; a name "
                                    "repeats only as the same point's other packing seeds")
            if seed in first["seeds"]:
                refuse(row, "name", f"duplicate: {name!r} with seed {seed if seed is not None else '(default)'} "
                                    f"is row {first['seeds'][seed]} already")
            first["seeds"][seed] = row
        else:
            name = f"{path.stem}_{i}"
        out.append({"name": name, "point": point, "preset": preset, "seed": seed})
    return out
