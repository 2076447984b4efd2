"""A plain, strict reader of the legacy ASCII VTK PolyData files that spreadmap.case.vtk_export
writes (the tests read back what was written with it)."""
from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np


class VtkPoints(NamedTuple):
    positions: np.ndarray  # (n, 3), m
    radius: np.ndarray  # (n,), m
    velocity: np.ndarray  # (n, 3), m/s


def read_vtk(path) -> dict:
    """Parse a legacy ASCII VTK PolyData file of points, as :func:`write_vtk` writes it.

    Returns ``{"version", "title", "dataset", "points" (n, 3), "vertices" (list of index
    lists), "point_data": {name: array}}`` (scalars with one component as (n,), vectors as
    (n, 3)).  Strict: a wrong header line, a dataset other than POLYDATA, binary data, or a
    count that disagrees with the numbers that follow raises ``ValueError``.
    """
    lines = Path(path).read_text(encoding="ascii").split("\n")
    if len(lines) < 4:
        raise ValueError(f"{path}: too short for a legacy VTK file")
    version = lines[0].strip()
    if not version.startswith("# vtk DataFile Version"):
        raise ValueError(f"{path}: first line is not a VTK header: {version!r}")
    title = lines[1].rstrip("\r")
    if lines[2].strip().upper() != "ASCII":
        raise ValueError(f"{path}: only ASCII files are read, found {lines[2].strip()!r}")
    head = lines[3].split()
    if len(head) != 2 or head[0].upper() != "DATASET":
        raise ValueError(f"{path}: fourth line must be 'DATASET <type>', found {lines[3]!r}")
    if head[1].upper() != "POLYDATA":
        raise ValueError(f"{path}: dataset {head[1]!r} is not POLYDATA")
    tokens = " ".join(lines[4:]).split()
    pos = 0

    def take(count: int, what: str) -> list[str]:
        nonlocal pos
        if pos + count > len(tokens):
            raise ValueError(f"{path}: {what}: expected {count} values, the file ends after {len(tokens) - pos}")
        out = tokens[pos:pos + count]
        pos += count
        return out

    def numbers(count: int, what: str) -> np.ndarray:
        try:
            return np.array([float(t) for t in take(count, what)], dtype=float)
        except ValueError as exc:
            raise ValueError(f"{path}: {what}: non-numeric value ({exc})") from None

    out: dict = {"version": version, "title": title, "dataset": "POLYDATA", "points": None,
                 "vertices": [], "point_data": {}}
    n_points = None
    n_data = None
    while pos < len(tokens):
        key = tokens[pos].upper()
        pos += 1
        if key == "POINTS":
            n_points, _dtype = int(take(1, "POINTS")[0]), take(1, "POINTS")[0]
            out["points"] = numbers(3 * n_points, "POINTS").reshape(n_points, 3)
        elif key == "VERTICES":
            n_cells, size = (int(t) for t in take(2, "VERTICES"))
            flat = [int(t) for t in take(size, "VERTICES")]
            cells, i = [], 0
            while i < len(flat):
                k = flat[i]
                cells.append(flat[i + 1:i + 1 + k])
                i += 1 + k
            if len(cells) != n_cells or i != size:
                raise ValueError(f"{path}: VERTICES header says {n_cells} cells / {size} values, "
                                 f"found {len(cells)} / {i}")
            if n_points is not None and any(not 0 <= j < n_points for c in cells for j in c):
                raise ValueError(f"{path}: a vertex refers to a point that does not exist")
            out["vertices"] = cells
        elif key == "POINT_DATA":
            n_data = int(take(1, "POINT_DATA")[0])
            if n_points is not None and n_data != n_points:
                raise ValueError(f"{path}: POINT_DATA {n_data} but {n_points} points")
        elif key == "SCALARS":
            if n_data is None:
                raise ValueError(f"{path}: SCALARS before POINT_DATA")
            name, _dtype = take(2, "SCALARS")
            ncomp = 1
            if pos < len(tokens) and tokens[pos].upper() != "LOOKUP_TABLE":
                ncomp = int(take(1, "SCALARS")[0])
            if pos < len(tokens) and tokens[pos].upper() == "LOOKUP_TABLE":
                take(2, "LOOKUP_TABLE")
            values = numbers(n_data * ncomp, f"SCALARS {name}")
            out["point_data"][name] = values if ncomp == 1 else values.reshape(n_data, ncomp)
        elif key in ("VECTORS", "NORMALS"):
            if n_data is None:
                raise ValueError(f"{path}: {key} before POINT_DATA")
            name, _dtype = take(2, key)
            out["point_data"][name] = numbers(3 * n_data, f"{key} {name}").reshape(n_data, 3)
        else:
            raise ValueError(f"{path}: unexpected keyword {tokens[pos - 1]!r}")
    if out["points"] is None:
        raise ValueError(f"{path}: no POINTS section")
    return out


def read_vtk_points(path) -> VtkPoints:
    """Sphere centres (n, 3), radii (n,) and velocities (n, 3) from a file written by
    :func:`write_vtk` (SI units)."""
    data = read_vtk(path)
    n = len(data["points"])
    pd_ = data["point_data"]
    radius = pd_.get("radius", np.full(n, np.nan))
    velocity = pd_.get("velocity", np.zeros((n, 3)))
    return VtkPoints(data["points"], np.asarray(radius, float), np.asarray(velocity, float))
