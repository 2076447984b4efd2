"""The 2-D slices of the design space, each defined once: which two axes vary, on what grid, and
where the others are held and why.

A map, a decision and the loop's criteria read the N-D model on a plane: two axes vary over a grid,
every other axis is held at one value (or, for a decision, at the points of a powder). Each such
plane is a ``Slice`` here, and the maps (``spreadmap.maps``), the decisions
(``spreadmap.decisions.feasibility``) and the loop's criteria (``spreadmap.loop.map_criteria``)
build their query points from it:

========================  ==================  ======================  ==========================================
slice                     varying (slowest    grid of the varying     fixed axes, from
                          first)              axes
========================  ==================  ======================  ==========================================
``MACHINE``               h_um, v_mm_s        maps.machine n_h, n_v   maps.machine (f 0.45, d_um 45)
                                              over the design range
``POWDER``                f, d_um             n_f 5, n_d 41 over the  maps.powder (h_um 57, v_mm_s 6.1)
                                              design range
``REGIME_PLANE``          d_um, h_um          n_d 60, n_h 40 over     maps.regime_plane (f 0.3, v_mm_s 10)
                                              the design range
``DECISIONS``             h_um, v_mm_s        decisions.machine:      the powder (decisions.powders.<name>:
                                              [low, high], n_h, n_v   its ``POWDER.varying`` axes, f and d_um)
========================  ==================  ======================  ==========================================

(the defaults are the schema's, schemas/config.schema.yaml). A fixed axis the config section does
not name -- any axis added to ``spreadmap.design.PARAMETERS`` after these four -- is held at its
nominal value (``Design.nominal``: ``Parameter.nominal``, else the middle of its range), so a new
axis reaches every slice without an edit here. ``box`` is the loop's third grid: cell centres
over the whole design box, every axis varying.

Points are in physical units, columns (or the last axis) in ``spreadmap.design.NAMES`` order, the
first varying axis slowest, then the second, then the fixed points (one for a map, a powder's for a
decision).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from . import design
from .design import Design
from .schema import checked


def axis_values(given, n: int, name: str, ranges=None, span=None) -> np.ndarray:
    """The values of one varying axis: the explicit ones if given (sorted), else ``n`` over a span.

    Parameters
    ----------
    given : array_like or None
        Explicit values in the parameter's unit; None: ``n`` values over the span.
    n : int
        How many values, both ends included (at least 2); used only without `given`.
    name : str
        The parameter (one of ``spreadmap.design.NAMES``).
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.
    span : sequence of two floats or None, optional
        ``[low, high]`` of the values (a config's machine limits); None: the design range.

    Returns
    -------
    numpy.ndarray
        The axis values, ascending, in the parameter's unit.

    Raises
    ------
    ValueError
        If `given` is empty, or `n` is below 2 without `given`.
    """
    if given is not None:
        v = np.asarray(given, float).ravel()
        if v.size == 0:
            raise ValueError(f"no values given for {name}")
        return np.sort(v)
    if n < 2:
        raise ValueError(f"grid size for {name} must be >= 2")
    if span is not None:
        return np.linspace(float(span[0]), float(span[1]), int(n))
    return Design.of(ranges).axis(name, int(n))


def size_key(name: str) -> str:
    """The config key of an axis's grid size.

    Parameters
    ----------
    name : str
        The parameter (one of ``spreadmap.design.NAMES``).

    Returns
    -------
    str
        ``n_`` and its symbol (``n_h`` for ``h_um``).
    """
    return f"n_{design.BY_NAME[name].symbol}"


@dataclass(frozen=True)
class Slice:
    """A 2-D slice of the design space.

    Parameters
    ----------
    name : str
        What reads it (``machine``, ``powder``, ``regime_plane``, ``decisions``).
    varying : tuple of two str
        The axes that vary, the first slowest (parameters of ``spreadmap.design.NAMES``).
    section : str
        The config section (dotted, as ``spreadmap.schema.checked`` takes it) that holds the fixed
        axes' values under the axes' names, the grid sizes under ``n_<symbol>`` and, for a decision,
        each varying axis's ``[low, high]`` under its name.
    sizes : dict of str to int
        Grid sizes of the varying axes where the section gives none.
    """

    name: str
    varying: tuple[str, str]
    section: str
    sizes: dict = field(default_factory=dict)

    def fixed_axes(self) -> tuple[str, ...]:
        """The axes held fixed.

        Returns
        -------
        tuple of str
            Every parameter of ``NAMES`` (read when called) but the varying two, in ``NAMES`` order.
        """
        return tuple(n for n in design.NAMES if n not in self.varying)

    def settings(self, config: Mapping | None = None) -> dict:
        """The slice's config section, the schema's defaults filled.

        Parameters
        ----------
        config : Mapping or None, optional
            A workflow config (its ``section`` is read; a missing one gives the defaults); None:
            the defaults.

        Returns
        -------
        dict
            The section.
        """
        part = config or {}
        for key in self.section.split("."):
            part = (part or {}).get(key) if isinstance(part, Mapping) else None
        return checked(self.section, part)

    def size(self, name: str, section: Mapping | None = None) -> int:
        """The grid size of a varying axis.

        Parameters
        ----------
        name : str
            The varying axis.
        section : Mapping or None, optional
            The slice's config section (``settings``); None: the slice's default alone.

        Returns
        -------
        int
            The section's ``n_<symbol>``, else the slice's default (``sizes``).
        """
        key = size_key(name)
        if section is not None and key in section:
            return int(section[key])
        return int(self.sizes[name])

    def fixed(self, values: Mapping | None = None, ranges=None) -> dict[str, float]:
        """The fixed axes' values: those given, every other at its nominal value.

        Parameters
        ----------
        values : Mapping or None, optional
            Values by axis name (the config section, or a map's keyword arguments); keys that are
            not fixed axes are ignored, a value of None counts as not given.
        ranges : Design, mapping or None, optional
            The design space whose nominal values fill the rest (``Design.nominal``).

        Returns
        -------
        dict of str to float
            One value per fixed axis, in ``NAMES`` order.
        """
        values = values or {}
        space = Design.of(ranges)
        return {n: space.nominal(n, values.get(n)) for n in self.fixed_axes()}

    def axes(self, section: Mapping | None = None, ranges=None, sizes: Mapping | None = None,
             given: Mapping | None = None) -> dict[str, np.ndarray]:
        """The varying axes' values.

        Parameters
        ----------
        section : Mapping or None, optional
            The slice's config section (``settings``): grid sizes ``n_<symbol>`` and, where it
            gives one, an axis's ``[low, high]`` (a decision's machine limits).
        ranges : Design, mapping or None, optional
            The design space, whose ranges an axis spans where the section gives no ``[low, high]``.
        sizes : Mapping or None, optional
            Grid sizes by axis name, over the section's and the slice's defaults; None values ignored.
        given : Mapping or None, optional
            Explicit values by axis name (sorted), instead of a grid.

        Returns
        -------
        dict of str to numpy.ndarray
            The values of each varying axis, in slice order.
        """
        section, sizes, given = section or {}, sizes or {}, given or {}
        out = {}
        for n in self.varying:
            span = section.get(n)
            span = span if isinstance(span, (list, tuple)) else None
            size = sizes.get(n) if sizes.get(n) is not None else self.size(n, section)
            out[n] = axis_values(given.get(n), size, n, ranges, span)
        return out

    def frame(self, axes: Mapping, fixed=None, ranges=None):
        """The slice's points: every pair of the varying axes' values, each with every fixed point.

        Parameters
        ----------
        axes : Mapping
            Values of each varying axis (``axes``).
        fixed : Mapping, pandas.DataFrame or None, optional
            The fixed axes: one value each (a mapping), or several points (a DataFrame's rows, e.g.
            a powder's range); an axis it leaves out is held at its nominal value.
        ranges : Design, mapping or None, optional
            The design space of those nominal values.

        Returns
        -------
        pandas.DataFrame
            Columns ``NAMES``; the first varying axis slowest, then the second, then the fixed points.
        """
        import pandas as pd  # here: the config's checks import this module on every workflow start

        mesh = np.meshgrid(*[np.atleast_1d(np.asarray(axes[n], float)) for n in self.varying], indexing="ij")
        pairs = np.column_stack([m.ravel() for m in mesh])
        if isinstance(fixed, pd.DataFrame):
            points = fixed.reset_index(drop=True)
            rest = self.fixed({}, ranges)
            points = pd.DataFrame({n: points[n].to_numpy(float) if n in points else np.full(len(points), rest[n])
                                   for n in self.fixed_axes()})
        else:
            points = pd.DataFrame([self.fixed(fixed, ranges)])
        m = len(points)
        cols = {n: np.repeat(pairs[:, k], m) for k, n in enumerate(self.varying)}
        cols.update({n: np.tile(points[n].to_numpy(float), len(pairs)) for n in self.fixed_axes()})
        return pd.DataFrame({n: cols[n] for n in design.NAMES})

    def points(self, config: Mapping | None = None, ranges=None, sizes: Mapping | None = None) -> np.ndarray:
        """The slice's query points as the config sets it (a map's slice; a decision's takes a powder).

        Parameters
        ----------
        config : Mapping or None, optional
            A workflow config: the slice's section (fixed values, grid sizes) and ``ranges``; None:
            the defaults.
        ranges : Design, mapping or None, optional
            The design space, instead of the config's ``ranges``.
        sizes : Mapping or None, optional
            Grid sizes by axis name, over the config's.

        Returns
        -------
        numpy.ndarray
            Shape (n, len(NAMES)), physical units, ``frame``'s order.
        """
        section = self.settings(config)
        space = Design.of(ranges if ranges is not None else (config or {}).get("ranges"))
        return self.frame(self.axes(section, space, sizes), self.fixed(section, space), space).to_numpy(float)

    def fixed_of(self, frame) -> dict[str, float]:
        """The fixed axes' values of a slice's table, e.g. a map's CSV read back (its titles read them so).

        Parameters
        ----------
        frame : pandas.DataFrame
            A table of the slice's points (``frame``, with whatever columns were added).

        Returns
        -------
        dict of str to float
            The first row's value of each fixed axis the table holds, in ``NAMES`` order.
        """
        return {n: float(frame[n].iloc[0]) for n in self.fixed_axes() if n in frame}


def text(values: Mapping[str, float], digits: int = 4) -> str:
    """Settings as the maps write them, in ``NAMES`` order.

    Parameters
    ----------
    values : Mapping
        Values by axis name (``Slice.fixed``).
    digits : int, optional
        Significant digits (``Parameter.text``).

    Returns
    -------
    str
        E.g. ``"f = 0.45, d = 45 um"``.
    """
    return ", ".join(design.BY_NAME[n].text(values[n], digits) for n in design.NAMES if n in values)


def box(ranges=None, k: int = 5) -> np.ndarray:
    """The design box's k^N cell centres (no face over-weighted), the first axis slowest.

    Parameters
    ----------
    ranges : Design, mapping or None, optional
        The design space; None: the default ranges.
    k : int, optional
        Cells per axis.

    Returns
    -------
    numpy.ndarray
        Shape (k^N, N), physical units, ``NAMES`` order.
    """
    centres = (np.arange(k) + 0.5) / k
    mesh = np.meshgrid(*[centres] * len(design.NAMES), indexing="ij")
    return Design.of(ranges).to_physical(np.column_stack([m.ravel() for m in mesh]))


MACHINE = Slice("machine", ("h_um", "v_mm_s"), "maps.machine")  # sizes: the section's n_h, n_v
POWDER = Slice("powder", ("f", "d_um"), "maps.powder", {"f": 5, "d_um": 41})
REGIME_PLANE = Slice("regime_plane", ("d_um", "h_um"), "maps.regime_plane", {"d_um": 60, "h_um": 40})
DECISIONS = Slice("decisions", MACHINE.varying, "decisions.machine")  # [low, high], n_h, n_v: the section's
SLICES: dict[str, Slice] = {s.name: s for s in (MACHINE, POWDER, REGIME_PLANE, DECISIONS)}
