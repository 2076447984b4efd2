"""The design space of a spreading study: four parameters, their ranges and units.

Tables, samples and figures all use these column names, in this order.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Parameter:
    name: str  # column name in every table
    symbol: str
    label: str  # axis label with unit, for figures
    low: float
    high: float
    unit: str


PARAMETERS: tuple[Parameter, ...] = (
    Parameter("f", "f", "inter-particle friction f [-]", 0.15, 0.45, "-"),
    Parameter("d_um", "d", "particle diameter d [um]", 10.0, 50.0, "um"),
    Parameter("h_um", "h", "layer thickness h [um]", 55.0, 75.0, "um"),
    Parameter("v_mm_s", "v", "blade speed v [mm/s]", 5.0, 15.0, "mm/s"),
)
NAMES: tuple[str, ...] = tuple(p.name for p in PARAMETERS)
BY_NAME: dict[str, Parameter] = {p.name: p for p in PARAMETERS}
TARGETS: tuple[str, ...] = ("mfr", "pd")


def bounds(ranges: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds in NAMES order; `ranges` (config) overrides the defaults.

    Parameters
    ----------
    ranges : dict or None, optional
        The config's ``ranges``: ``{name: {"min": ..., "max": ...}}`` in each parameter's unit
        (f [-], d_um [um], h_um [um], v_mm_s [mm/s]); a name or a bound it leaves out keeps the
        default of ``PARAMETERS``. None: the defaults.

    Returns
    -------
    low, high : tuple of numpy.ndarray
        Two float arrays of shape (4,), in NAMES order, in physical units.
    """
    ranges = ranges or {}
    low = np.array([ranges.get(n, {}).get("min", BY_NAME[n].low) for n in NAMES], float)
    high = np.array([ranges.get(n, {}).get("max", BY_NAME[n].high) for n in NAMES], float)
    return low, high


def to_physical(unit_points: np.ndarray, ranges: dict | None = None) -> np.ndarray:
    """Map points of the unit hypercube [0, 1]^4 to parameter values.

    Parameters
    ----------
    unit_points : numpy.ndarray
        Points in [0, 1]^4, shape (n, 4) (or (4,)), columns in NAMES order.
    ranges : dict or None, optional
        The config's ``ranges`` (see ``bounds``); None: the defaults.

    Returns
    -------
    numpy.ndarray
        The points in physical units (f [-], d_um [um], h_um [um], v_mm_s [mm/s]), same shape.
    """
    low, high = bounds(ranges)
    return low + np.asarray(unit_points, float) * (high - low)


def to_unit(points: np.ndarray, ranges: dict | None = None) -> np.ndarray:
    """Map parameter values to the unit hypercube (inverse of to_physical).

    Parameters
    ----------
    points : numpy.ndarray
        Points in physical units, shape (n, 4) (or (4,)), columns in NAMES order.
    ranges : dict or None, optional
        The config's ``ranges`` (see ``bounds``); None: the defaults.

    Returns
    -------
    numpy.ndarray
        The points scaled to [0, 1] per parameter (outside it for points outside the ranges),
        same shape.
    """
    low, high = bounds(ranges)
    return (np.asarray(points, float) - low) / (high - low)
