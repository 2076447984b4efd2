"""The design space of a spreading study: four parameters, their ranges and units.

Tables, samples and figures all use these column names, in this order.

``Design`` is the one object that holds a study's design space: built once from the config
(``Design.from_config``), it gives the names, the ranges, the maps to and from the unit cube,
evenly spaced axes and the gap-to-diameter ratio h/d that the physics reads.

``PARAMETERS`` is the axes' one home: name, symbol, figure label, default range, unit and the
nominal value an axis takes where a map or a decision holds it fixed and the config names no value
(``Design.nominal``). The 2-D slices the maps, the decisions and the loop's criteria read are
defined once, over these axes, in ``spreadmap.slices``. The module globals ``PARAMETERS``,
``NAMES`` and ``BY_NAME`` are read when called (``Design``, ``spreadmap.slices``,
``spreadmap.sampling``, ``spreadmap.maps.grids``), so an axis registered here reaches them
(tests/core/test_slices.py adds a toy fifth axis).  Every function of
the package that takes a ``ranges`` argument takes a ``Design`` (or, as before, the config's
``ranges`` mapping, or None for the defaults of ``PARAMETERS``); ``Design.of`` is that rule.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .targets import names as target_names


@dataclass(frozen=True)
class Parameter:
    """One design axis: its names, its default range and unit, and where a slice holds it.

    Parameters
    ----------
    name : str
        Its column name in every table (and its config key).
    symbol : str
        The symbol the maps write (``v`` in ``v = 6.1 mm/s``); ``n_<symbol>`` is its grid size's
        config key.
    label : str
        Its axis label, with its unit, for figures.
    low, high : float
        Its default range, in its unit (config ``ranges`` overrides it).
    unit : str
        Its unit (``-`` for none).
    nominal : float or None, optional
        Its value where a slice holds it fixed and the config names none; None: the middle of its
        range.
    """

    name: str  # column name in every table
    symbol: str
    label: str  # axis label with unit, for figures
    low: float
    high: float
    unit: str
    nominal: float | None = None  # where a slice holds it fixed and the config names no value; None: mid-range

    def text(self, value: float, digits: int = 4) -> str:
        """``symbol = value unit`` as the maps write a setting, e.g. ``"v = 6.1 mm/s"`` (no unit for [-]).

        Parameters
        ----------
        value : float
            The parameter's value, in its unit.
        digits : int, optional
            Significant digits (``g`` format).

        Returns
        -------
        str
            The setting as text.
        """
        unit = "" if self.unit == "-" else f" {self.unit}"
        return f"{self.symbol} = {value:.{digits}g}{unit}"


PARAMETERS: tuple[Parameter, ...] = (
    Parameter("f", "f", "inter-particle friction f [-]", 0.15, 0.45, "-"),
    Parameter("d_um", "d", "particle diameter d [um]", 10.0, 50.0, "um"),
    Parameter("h_um", "h", "layer thickness h [um]", 55.0, 75.0, "um"),
    Parameter("v_mm_s", "v", "blade speed v [mm/s]", 5.0, 15.0, "mm/s"),
)
NAMES: tuple[str, ...] = tuple(p.name for p in PARAMETERS)
BY_NAME: dict[str, Parameter] = {p.name: p for p in PARAMETERS}
TARGETS: tuple[str, ...] = target_names("base")  # mfr, pd (spreadmap.targets)


@dataclass(frozen=True)
class Design:
    """A study's design space: the four parameters of ``PARAMETERS`` with the config's ranges.

    Parameters
    ----------
    low, high : tuple of float
        Lower and upper bounds in NAMES order, in each parameter's unit (f [-], d_um [um],
        h_um [um], v_mm_s [mm/s]); ``low < high`` for each.

    Raises
    ------
    ValueError
        If a bound is not finite or a lower bound is not below its upper bound.
    """

    low: tuple[float, ...]
    high: tuple[float, ...]

    def __post_init__(self):
        low, high = np.asarray(self.low, float), np.asarray(self.high, float)
        if low.shape != (len(NAMES),) or high.shape != (len(NAMES),):
            raise ValueError(f"a design has {len(NAMES)} bounds each ({', '.join(NAMES)})")
        bad = [n for n, a, b in zip(NAMES, low, high, strict=True) if not (np.isfinite(a) and np.isfinite(b) and a < b)]
        if bad:
            raise ValueError(f"design range of {', '.join(bad)}: min must be finite and below max")
        object.__setattr__(self, "low", tuple(float(x) for x in low))
        object.__setattr__(self, "high", tuple(float(x) for x in high))

    @classmethod
    def from_ranges(cls, ranges: Mapping | None = None) -> Design:
        """The design space of the config's ``ranges`` mapping.

        Parameters
        ----------
        ranges : mapping or None, optional
            ``{name: {"min": ..., "max": ...}}`` in each parameter's unit; a name or a bound it
            leaves out keeps the default of ``PARAMETERS``. None: the defaults.

        Returns
        -------
        Design
            The design space.
        """
        ranges = ranges or {}
        low = [ranges.get(n, {}).get("min", BY_NAME[n].low) for n in NAMES]
        high = [ranges.get(n, {}).get("max", BY_NAME[n].high) for n in NAMES]
        return cls(tuple(low), tuple(high))

    @classmethod
    def from_config(cls, config: Mapping | None) -> Design:
        """The design space of a workflow config (its ``ranges`` section; None: the defaults).

        Parameters
        ----------
        config : mapping or None
            A workflow config (``spreadmap.config.load``).

        Returns
        -------
        Design
            The design space.
        """
        return cls.from_ranges((config or {}).get("ranges"))

    @classmethod
    def of(cls, design: Design | Mapping | None) -> Design:
        """``design`` itself if it is a Design, else the Design of a ``ranges`` mapping (None: defaults).

        Parameters
        ----------
        design : Design, mapping or None
            A design space, or the config's ``ranges`` mapping, or None.

        Returns
        -------
        Design
            The design space.
        """
        return design if isinstance(design, Design) else cls.from_ranges(design)

    @property
    def names(self) -> tuple[str, ...]:
        """The parameters' column names, in order (``NAMES``)."""
        return NAMES

    @property
    def ranges(self) -> dict[str, dict[str, float]]:
        """The design space as the config writes it: ``{name: {"min": ..., "max": ...}}``."""
        return {n: {"min": a, "max": b} for n, a, b in zip(NAMES, self.low, self.high, strict=True)}

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds.

        Returns
        -------
        low, high : tuple of numpy.ndarray
            Two float arrays of shape (4,), in NAMES order, in physical units.
        """
        return np.array(self.low, float), np.array(self.high, float)

    def to_physical(self, unit_points: np.ndarray) -> np.ndarray:
        """Points of the unit cube in physical units.

        Parameters
        ----------
        unit_points : numpy.ndarray
            Points in [0, 1]^4, shape (n, 4) or (4,), columns in NAMES order.

        Returns
        -------
        numpy.ndarray
            ``low + unit_points * (high - low)``: f [-], d_um [um], h_um [um], v_mm_s [mm/s]; same shape.
        """
        low, high = self.bounds()
        return low + np.asarray(unit_points, float) * (high - low)

    def to_unit(self, points: np.ndarray) -> np.ndarray:
        """Points in physical units scaled to the unit cube (the inverse of ``to_physical``).

        Parameters
        ----------
        points : numpy.ndarray
            Points in physical units, shape (n, 4) or (4,), columns in NAMES order.

        Returns
        -------
        numpy.ndarray
            ``(points - low) / (high - low)``, same shape (outside [0, 1] for points outside the ranges).
        """
        low, high = self.bounds()
        return (np.asarray(points, float) - low) / (high - low)

    def axis(self, name: str, n: int) -> np.ndarray:
        """Evenly spaced values of one parameter over its range, both ends included.

        Parameters
        ----------
        name : str
            The parameter (one of ``NAMES``).
        n : int
            How many values.

        Returns
        -------
        numpy.ndarray
            ``numpy.linspace(low, high, n)`` of the parameter, in its unit.
        """
        i = NAMES.index(name)
        return np.linspace(self.low[i], self.high[i], n)

    def label(self, name: str) -> str:
        """The axis label of one parameter, with its unit (for figures).

        Parameters
        ----------
        name : str
            The parameter (one of ``NAMES``).

        Returns
        -------
        str
            Its ``Parameter.label``, e.g. ``"blade speed v [mm/s]"``.
        """
        return BY_NAME[name].label

    def nominal(self, name: str, given: float | None = None) -> float:
        """The value one parameter is held at where a slice fixes it.

        Parameters
        ----------
        name : str
            The parameter (one of ``NAMES``).
        given : float or None, optional
            The value the config names for it; None: it names none.

        Returns
        -------
        float
            `given` if not None, else the parameter's ``Parameter.nominal``, else the middle of its
            range in this design.
        """
        if given is not None:
            return float(given)
        i = NAMES.index(name)
        return float(BY_NAME[name].nominal) if BY_NAME[name].nominal is not None else (self.low[i] + self.high[i]) / 2


def h_over_d(points) -> np.ndarray:
    """The gap-to-diameter ratio h/d [-] of design points: the one place it is computed.

    Parameters
    ----------
    points : pandas.DataFrame, mapping or numpy.ndarray
        Anything with ``h_um`` and ``d_um`` columns (or keys), both in um; or an array of points
        whose last axis holds the parameters in ``NAMES`` order, shape (n, 4) or (4,).

    Returns
    -------
    numpy.ndarray
        h_um / d_um, as floats (shape (n,), or () for one point).
    """
    if isinstance(points, np.ndarray):
        points = np.asarray(points, float)
        return points[..., NAMES.index("h_um")] / points[..., NAMES.index("d_um")]
    return np.asarray(points["h_um"], float) / np.asarray(points["d_um"], float)


def bounds(ranges: Design | Mapping | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds in NAMES order; `ranges` (config) overrides the defaults.

    Parameters
    ----------
    ranges : Design, mapping or None, optional
        The design space (``Design.of``): a Design, or the config's ``ranges``
        ``{name: {"min": ..., "max": ...}}`` in each parameter's unit (f [-], d_um [um], h_um [um],
        v_mm_s [mm/s]), where a name or a bound left out keeps the default of ``PARAMETERS``.
        None: the defaults.

    Returns
    -------
    low, high : tuple of numpy.ndarray
        Two float arrays of shape (4,), in NAMES order, in physical units.
    """
    return Design.of(ranges).bounds()


def to_physical(unit_points: np.ndarray, ranges: Design | Mapping | None = None) -> np.ndarray:
    """Map points of the unit hypercube [0, 1]^4 to parameter values.

    Parameters
    ----------
    unit_points : numpy.ndarray
        Points in [0, 1]^4, shape (n, 4) (or (4,)), columns in NAMES order.
    ranges : Design, mapping or None, optional
        The design space (see ``bounds``); None: the defaults.

    Returns
    -------
    numpy.ndarray
        The points in physical units (f [-], d_um [um], h_um [um], v_mm_s [mm/s]), same shape.
    """
    return Design.of(ranges).to_physical(unit_points)


def to_unit(points: np.ndarray, ranges: Design | Mapping | None = None) -> np.ndarray:
    """Map parameter values to the unit hypercube (inverse of to_physical).

    Parameters
    ----------
    points : numpy.ndarray
        Points in physical units, shape (n, 4) (or (4,)), columns in NAMES order.
    ranges : Design, mapping or None, optional
        The design space (see ``bounds``); None: the defaults.

    Returns
    -------
    numpy.ndarray
        The points scaled to [0, 1] per parameter (outside it for points outside the ranges),
        same shape.
    """
    return Design.of(ranges).to_unit(points)
