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
doubles exactly.  Files are written atomically and durably (spreadmap.files: a temporary file in
the same folder, flushed to disk, then renamed): a reader never sees half a file.

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
* :func:`export_case` -- every snapshot of a raw result to ``<outdir>/<moment>.vtk``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..files import write_text_atomically

__all__ = ["write_vtk", "export_case", "MOMENT_ORDER"]

# Chronological order of the snapshot moments a raw result can hold.
MOMENT_ORDER = ("settled", "blade_start", "window_start", "window_middle", "window_end")

_HEADER = "# vtk DataFile Version 3.0"


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

    Open the file in ParaView; see the module docstring for the format and for drawing the points
    as spheres.

    Parameters
    ----------
    snapshot : dict
        ``positions`` [[x, y, z], ...] (m), ``radii`` [...] (m) and, optionally, ``velocities``
        [[vx, vy, vz], ...] (m/s; zeros if absent).
    path : pathlib.Path or str
        The file to write; its folder is created if missing.
    title : str, optional
        The header's title line (white space folded to one line, at most 255 characters; empty:
        the default).

    Returns
    -------
    pathlib.Path
        The path.

    Raises
    ------
    ValueError
        If the snapshot's positions, radii and velocities disagree in number.
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
    write_text_atomically(path, "".join(parts), encoding="ascii")
    return path


def _moment_key(raw_snapshots: dict, name: str) -> tuple:
    t = raw_snapshots[name].get("time")
    order = MOMENT_ORDER.index(name) if name in MOMENT_ORDER else len(MOMENT_ORDER)
    return (order, t if isinstance(t, (int, float)) else 0.0, name)


def export_case(raw: dict, outdir) -> list[Path]:
    """Write every snapshot of a raw result as ``<outdir>/<moment>.vtk`` (e.g. ``window_end.vtk``).

    Open the files in ParaView (legacy VTK reader). Each file's title names the case, the moment
    and its time.

    Parameters
    ----------
    raw : dict
        The case's raw result: its ``snapshots`` (moment -> ``write_vtk``'s snapshot, with its
        ``time`` [s]) and ``params`` (``case_id``).
    outdir : pathlib.Path or str
        The folder of the files (created if missing).

    Returns
    -------
    list of pathlib.Path
        The paths in chronological order of the moments (settled, blade_start, window_start,
        window_middle, window_end, then any other moment by name); empty for a raw result without
        snapshots.

    Raises
    ------
    ValueError
        If a snapshot's arrays disagree in number (``write_vtk``).
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
