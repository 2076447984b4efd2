"""Sample tables of the design space.

LDS: scrambled Halton in 4-D (scipy.stats.qmc.Halton), seeded. Points are generated in sequence,
so case i is the same point whatever the total N: LDS-N is a prefix of LDS-2N and growing a
sweep only adds cases. Lattice: k points per dimension, end points included, k^4 cases.
"""
from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
from scipy.stats import qmc

from .design import NAMES, to_physical


def halton_unit(n: int, seed: int) -> np.ndarray:
    """The first n points of the seeded scrambled Halton sequence in [0, 1)^4."""
    return qmc.Halton(d=len(NAMES), scramble=True, seed=seed).random(n)


def lattice_unit(k: int) -> np.ndarray:
    """k^4 points: every combination of k equally spaced values per dimension, ends included."""
    if k < 2:
        raise ValueError(f"a lattice needs k >= 2 points per dimension (k = {k})")
    axis = np.linspace(0.0, 1.0, k)
    return np.array(list(itertools.product(axis, repeat=len(NAMES))))


def _table(unit: np.ndarray, ranges: dict | None) -> pd.DataFrame:
    table = pd.DataFrame(to_physical(unit, ranges), columns=list(NAMES))
    table.insert(0, "index", np.arange(len(table)))
    return table


def halton(n: int, seed: int, ranges: dict | None = None) -> pd.DataFrame:
    """LDS sample table: columns index, f, d_um, h_um, v_mm_s."""
    return _table(halton_unit(n, seed), ranges)


def lattice(k: int, ranges: dict | None = None) -> pd.DataFrame:
    """Uniform lattice sample table with k points per dimension (k^4 rows)."""
    return _table(lattice_unit(k), ranges)


def chosen_points(points_config: dict | None, base_dir=".") -> list[dict]:
    """The user's chosen points: config `points.named` then the rows of `points.csv`.
    Each entry: {"name", "point": {f, d_um, h_um, v_mm_s}, "preset" or None, "seed" or None}."""
    from pathlib import Path

    points_config = points_config or {}
    out = []
    for name, entry in (points_config.get("named") or {}).items():
        out.append({"name": str(name), "point": {k: float(entry[k]) for k in NAMES},
                    "preset": entry.get("preset"), "seed": entry.get("seed")})
    csv = points_config.get("csv")
    if csv:
        path = Path(base_dir) / csv
        if not path.exists():
            raise ValueError(f"config key 'points.csv': file {str(path)!r} does not exist")
        table = pd.read_csv(path)
        missing = [c for c in NAMES if c not in table.columns]
        if missing:
            raise ValueError(f"points CSV {path}: missing column(s) {missing}; required: {list(NAMES)}")
        for i, row in table.iterrows():
            point = {}
            for k in NAMES:
                value = pd.to_numeric(row[k], errors="coerce")
                if not (np.isfinite(value) and value > 0):
                    raise ValueError(f"points CSV {path}, row {i + 2}: {k} = {row[k]!r} is not a positive number")
                point[k] = float(value)
            preset = row.get("preset") if "preset" in table.columns and isinstance(row.get("preset"), str) else None
            seed = None
            if "seed" in table.columns and pd.notna(row.get("seed")):
                value = pd.to_numeric(row["seed"], errors="coerce")
                if not (np.isfinite(value) and value >= 0 and float(value).is_integer()):
                    raise ValueError(f"points CSV {path}, row {i + 2}: seed = {row['seed']} is not allowed; "
                                     "a packing seed is an integer >= 0 (YADE seeds a negative one from the clock)")
                seed = int(value)
            name = str(row["name"]) if "name" in table.columns and pd.notna(row.get("name")) else f"{path.stem}_{i}"
            out.append({"name": name, "point": point, "preset": preset, "seed": seed})
    return out
