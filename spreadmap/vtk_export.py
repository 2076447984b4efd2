"""Sphere snapshots as legacy VTK files, for 3-D viewing in ParaView (or VisIt, or anything that
reads VTK).

File format
-----------
One ASCII file per snapshot in the *legacy* VTK format (``# vtk DataFile Version 3.0``), dataset
``POLYDATA``:

* ``POINTS n double`` -- the sphere centres, in metres (SI, as in the raw result);
* ``VERTICES n 2n`` -- one vertex cell per sphere, so the points render without a filter;
* ``POINT_DATA n`` with ``SCALARS radius double 1`` (m), ``SCALARS speed double 1`` (|v|, m/s)
  and ``VECTORS velocity double`` (m/s).

Numbers are written with 17 significant digits, so reading a file back reproduces the raw
doubles exactly.  Files are written atomically (a temporary file in the same folder, then
``os.replace``): a reader never sees half a file.

Viewing in ParaView
-------------------
ParaView opens legacy ``.vtk`` files directly (File > Open, "Legacy VTK Reader").  To see the
spheres as spheres: apply the *Glyph* filter, glyph type Sphere, Orientation off, Scale Array
``radius``, Scale Factor 2 (ParaView's unit sphere glyph has radius 0.5), Glyph Mode "All Points";
colour by ``speed``.  Quicker: representation "Point Gaussian", Scale by array ``radius``
(Gaussian Radius 1).  The blade and floor are not in these files; x is the travel direction,
z = 0 the floor, side walls at y = 0 and y = width.

Functions
---------
* :func:`write_vtk` -- one snapshot dict (``positions``, ``radii``, ``velocities``) to a file;
* :func:`read_vtk` / :func:`read_vtk_points` -- a plain, strict parser of exactly this kind of
  file (used by the tests to check that what was written loads);
* :func:`export_case` -- every snapshot of a raw result to ``<outdir>/<moment>.vtk``.
"""
from __future__ import annotations

import os
import uuid
from pathlib import Path
from typing import NamedTuple

import numpy as np

__all__ = ["write_vtk", "read_vtk", "read_vtk_points", "export_case", "VtkPoints", "MOMENT_ORDER"]

# Chronological order of the snapshot moments a raw result can hold.
MOMENT_ORDER = ("settled", "blade_start", "window_start", "window_middle", "window_end")

_HEADER = "# vtk DataFile Version 3.0"


class VtkPoints(NamedTuple):
    positions: np.ndarray  # (n, 3), m
    radius: np.ndarray  # (n,), m
    velocity: np.ndarray  # (n, 3), m/s


def _snapshot_arrays(snapshot: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    pos = np.asarray(snapshot.get("positions", []), dtype=float).reshape(-1, 3)
    n = len(pos)
    rad = np.asarray(snapshot.get("radii", []), dtype=float).reshape(-1)
    vel = snapshot.get("velocities")
    vel = np.zeros((n, 3)) if vel is None else np.asarray(vel, dtype=float).reshape(-1, 3)
    if rad.shape != (n,) or vel.shape != (n, 3):
        raise ValueError(f"snapshot arrays disagree: {n} positions, {rad.size} radii, {len(vel)} velocities")
    return pos, rad, vel


def _fmt(values: np.ndarray) -> str:
    """Rows of numbers, 17 significant digits (a double round-trips exactly)."""
    values = np.atleast_2d(values)
    return "".join(" ".join(format(float(v), ".17g") for v in row) + "\n" for row in values)


def write_vtk(snapshot: dict, path, title: str = "spreadmap spheres") -> Path:
    """Write one snapshot's spheres as a legacy ASCII VTK PolyData file at ``path`` (atomically).

    ``snapshot`` holds ``positions`` [[x, y, z], ...] (m), ``radii`` [...] (m) and, optionally,
    ``velocities`` [[vx, vy, vz], ...] (m/s; zeros if absent).  ``title`` goes on the header's
    title line (one line, at most 255 characters).  Open the file in ParaView; see the module
    docstring for drawing the points as spheres.  Returns the path.
    """
    pos, rad, vel = _snapshot_arrays(snapshot)
    n = len(pos)
    speed = np.linalg.norm(vel, axis=1) if n else np.zeros(0)
    title = " ".join(str(title).split())[:255] or "spreadmap spheres"
    parts = [
        _HEADER + "\n", title + "\n", "ASCII\n", "DATASET POLYDATA\n",
        f"POINTS {n} double\n", _fmt(pos) if n else "",
        f"VERTICES {n} {2 * n}\n", "".join(f"1 {i}\n" for i in range(n)),
        f"POINT_DATA {n}\n",
        "SCALARS radius double 1\n", "LOOKUP_TABLE default\n", _fmt(rad[:, None]) if n else "",
        "SCALARS speed double 1\n", "LOOKUP_TABLE default\n", _fmt(speed[:, None]) if n else "",
        "VECTORS velocity double\n", _fmt(vel) if n else "",
    ]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # a unique temporary name in the same folder (so os.replace is atomic); plain open() keeps
    # the usual permissions (umask), unlike tempfile.mkstemp's 0600
    tmp = path.parent / f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp"
    try:
        with open(tmp, "x", encoding="ascii", newline="\n") as fh:
            fh.write("".join(parts))
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


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


def _moment_key(raw_snapshots: dict, name: str) -> tuple:
    t = raw_snapshots[name].get("time")
    order = MOMENT_ORDER.index(name) if name in MOMENT_ORDER else len(MOMENT_ORDER)
    return (order, t if isinstance(t, (int, float)) else 0.0, name)


def export_case(raw: dict, outdir) -> list[Path]:
    """Write every snapshot of a raw result as ``<outdir>/<moment>.vtk`` (e.g. ``window_end.vtk``).

    Returns the paths in chronological order of the moments (settled, blade_start,
    window_start, window_middle, window_end, then any other moment by name).  A raw result
    without snapshots gives an empty list.  Open the files in ParaView (legacy VTK reader).
    """
    snapshots = raw.get("snapshots") or {}
    case = (raw.get("params") or {}).get("case_id", "")
    outdir = Path(outdir)
    paths = []
    for name in sorted(snapshots, key=lambda m: _moment_key(snapshots, m)):
        snap = snapshots[name]
        t = snap.get("time")
        when = f" t = {t:.9g} s" if isinstance(t, (int, float)) else ""
        title = f"spreadmap spheres case {case} moment {name}{when} (SI units)"
        paths.append(write_vtk(snap, outdir / f"{name}.vtk", title=title))
    return paths
