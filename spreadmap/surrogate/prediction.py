"""Predictions at chosen points: the mean, the model's SD and the SD a new DEM run would show.

Points come as a DataFrame or mapping with the columns f, d_um, h_um, v_mm_s (the README's points
format may add ``name``, ``preset`` and ``seed``: accepted, ``name`` is carried to the output),
or as an (n, 4) array in that order. What no physical setting can be is refused: a diameter, gap
or speed that is not positive, a negative friction coefficient, or one above ``F_MAX`` = 5 (a
friction angle above 79 degrees: dry metal-on-metal sliding friction stays below ~1, and even clean
metals in vacuum, which cold-weld, are reported near 1-2, so a value above 5 is a typo, not a
powder). What is physical but outside what the surrogate knows is predicted and warned about:
a parameter outside the design ranges the model was trained for, a gap narrower than one particle
(h < d: nothing can pass, the case jams by construction, and no training case is there), and a
point far from every training case (``data_distance`` above ``MAX_DISTANCE`` median spacings).
"""
from __future__ import annotations

import warnings
from collections.abc import Mapping

import numpy as np
import pandas as pd

from ..design import BY_NAME, NAMES
from .saved_model import SurrogateModel

POINT_EXTRAS = ("name", "preset", "seed")   # columns of the README's points format besides NAMES
F_MAX = 5.0
MAX_DISTANCE = 1.5


class OutOfRangeWarning(UserWarning):
    """A point outside what the surrogate was trained on (design ranges, data, or h < d)."""


def _numeric(values, name: str) -> np.ndarray:
    arr = np.asarray(values)
    if arr.dtype.kind in "fiu":
        return arr.astype(float)
    for i, v in enumerate(arr.ravel()):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise ValueError(f"parameter {name!r} must be numeric; got {v!r} ({type(v).__name__}) at row {i}")
    return arr.astype(float)


def as_points(points) -> tuple[np.ndarray, list | None]:
    """(n, 4) float array in NAMES order and the points' names (None if not given)."""
    expected = ", ".join(NAMES)
    names = None
    if isinstance(points, Mapping) and not isinstance(points, pd.DataFrame):
        try:
            points = pd.DataFrame({k: np.atleast_1d(np.asarray(v, dtype=object)) for k, v in points.items()})
        except ValueError as e:
            raise ValueError(f"parameter values of unequal length: {e}") from None
    if isinstance(points, pd.DataFrame):
        cols = [str(c) for c in points.columns]
        if len(set(cols)) != len(cols):
            raise ValueError(f"duplicate column names {cols}")
        unknown = [c for c in cols if c not in NAMES and c not in POINT_EXTRAS]
        missing = [n for n in NAMES if n not in cols]
        if unknown:
            raise ValueError(f"unknown column(s) {unknown}; expected {expected} (and optionally "
                             f"{', '.join(POINT_EXTRAS)})")
        if missing:
            raise ValueError(f"missing column(s) {missing}; expected {expected}")
        if "name" in cols:
            names = points["name"].astype(str).tolist()
        X = (np.column_stack([_numeric(points[n].to_numpy(), n) for n in NAMES]) if len(points)
             else np.empty((0, len(NAMES))))
    else:
        if isinstance(points, (str, bytes)):
            raise ValueError(f"points must be numbers ({expected}), got the string {points!r}")
        try:
            arr = np.asarray(points)
            if arr.dtype.kind not in "fiu" or not isinstance(points, np.ndarray):
                arr = np.asarray(points, dtype=object)
        except ValueError as e:
            raise ValueError(f"points are not a rectangular table: {e}") from None
        if arr.ndim == 1:
            arr = arr.reshape(1, -1)
        if arr.ndim != 2 or arr.shape[1] != len(NAMES):
            raise ValueError(f"points must have {len(NAMES)} columns ({expected}); got shape {arr.shape}")
        X = (np.column_stack([_numeric(arr[:, j], n) for j, n in enumerate(NAMES)]) if len(arr)
             else np.empty((0, len(NAMES))))
    if X.shape[0] == 0:
        raise ValueError("no points to predict")
    bad = ~np.isfinite(X)
    if bad.any():
        i, j = map(int, np.argwhere(bad)[0])
        raise ValueError(f"non-finite value {X[i, j]} for parameter {NAMES[j]!r} at row {i}")
    refuse_unphysical(X)
    return X, names


def refuse_unphysical(X: np.ndarray) -> None:
    """ValueError for the first value no physical setting can have (see the module docstring)."""
    f = X[:, 0]
    rules = [(f < 0, "f", "a friction coefficient cannot be negative"),
             (f > F_MAX, "f", f"a friction coefficient above {F_MAX:g} (friction angle > 79 deg) is no powder")]
    for j, name in enumerate(NAMES[1:], start=1):
        rules.append((X[:, j] <= 0, name, f"{BY_NAME[name].label.split(' [')[0]} must be positive"))
    for bad, name, why in rules:
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"point {i}: {name} = {X[i, NAMES.index(name)]:g} is refused: {why}")


def _warn_points(model: SurrogateModel, X: np.ndarray, distance: np.ndarray) -> list[str]:
    msgs = []
    out = model.outside_design(X)
    for j, name in enumerate(NAMES):
        rows = np.flatnonzero(out[:, j])
        if len(rows):
            i = int(rows[np.argmax(np.abs(X[rows, j] - (model.design_low[j] + model.design_high[j]) / 2))])
            unit = "" if BY_NAME[name].unit == "-" else f" {BY_NAME[name].unit}"
            msgs.append(f"{len(rows)} of {len(X)} point(s) outside the design range of {name} "
                        f"[{model.design_low[j]:g}, {model.design_high[j]:g}]{unit}, e.g. {name} = {X[i, j]:g} "
                        f"at row {i}: the surrogate has no data there and extrapolates")
    gap = np.flatnonzero(X[:, 2] < X[:, 1])
    if len(gap):
        i = int(gap[0])
        msgs.append(f"{len(gap)} point(s) with a gap narrower than one particle, e.g. h = {X[i, 2]:g} um < "
                    f"d = {X[i, 1]:g} um at row {i}: such a case jams by construction (MFR = 0) and the "
                    "surrogate has no case there")
    far = np.flatnonzero(distance > MAX_DISTANCE)
    if len(far):
        i = int(far[np.argmax(distance[far])])
        msgs.append(f"{len(far)} point(s) far from every training case (up to {distance[i]:.2g} median "
                    f"spacings, row {i}; supported up to {MAX_DISTANCE:g}): treat as extrapolation")
    return msgs


def predict(model: SurrogateModel, points) -> pd.DataFrame:
    """Per point: the inputs, per target ``<t>`` (mean), ``<t>_model_sd`` (what the model does not
    know), ``<t>_run_sd`` (SD of a new DEM run there: model and noise); ``data_distance`` (median
    spacings to the nearest training case), ``outside_design`` (parameter names, ';'-joined),
    ``gap_below_d``, ``supported``. Warns (OutOfRangeWarning) as the module docstring says."""
    if not isinstance(model, SurrogateModel):
        raise TypeError(f"model must be a SurrogateModel, got {type(model).__name__}")
    X, names = as_points(points)
    distance = model.data_distance(X)
    for msg in _warn_points(model, X, distance):
        warnings.warn(msg, OutOfRangeWarning, stacklevel=2)
    out = pd.DataFrame(X, columns=list(NAMES))
    if names is not None:
        out.insert(0, "name", names)
    for t, (mean, msd, rsd) in model.predict_stats(X).items():
        out[t], out[f"{t}_model_sd"], out[f"{t}_run_sd"] = mean, msd, rsd
    oor = model.outside_design(X)
    out["data_distance"] = distance
    out["outside_design"] = [";".join(n for n, b in zip(NAMES, r) if b) for r in oor]
    out["gap_below_d"] = X[:, 2] < X[:, 1]
    out["supported"] = (distance <= MAX_DISTANCE) & ~oor.any(axis=1) & ~out["gap_below_d"].to_numpy()
    return out
