"""The floor a case is spread on, and the gap measured over it.

Two floors (config ``scene.substrate``, yade_scripts/spreading_case.py): ``flat``, the study's
smooth floor, whose face is z = 0; ``rough``, the previous layer: fixed spheres of the powder's
diameter d (radius R) on a hexagonal lattice (rows along x at pitch d, rows sqrt(3) R apart,
alternate rows shifted by d/2: every sphere touches its six neighbours), each lowered by a uniform
random depth in [0, jitter R], so that their tops lie in [-jitter R, 0]. The gap h is measured from
z = 0 on both floors.

Nominal and effective gap
-------------------------
On the rough floor powder also fills the substrate's hollows below z = 0. The effective gap is the
nominal gap plus the mean depth of the substrate's upper surface below z = 0:

    h_eff = h + D d,    D = mean over the plane of (0 - s(x, y)) / d,

with s(x, y) the height of the highest sphere cap over (x, y), averaged over the random depths.

D in closed form. Neighbouring spheres are 2 R apart, so the discs their caps project onto the
plane (radius R) touch but never overlap: over each point lies at most one cap, and the "highest
cap" is that one cap. Over its disc, a sphere lowered by u R is at depth u R + R - sqrt(R^2 - r^2);
the mean of R - sqrt(R^2 - r^2) over the disc is R/3, and the mean of u is jitter / 2, so

    D = 1/6 + jitter / 4      (in d; 1/6 = 0.1667 at jitter 0, 7/24 = 0.2917 at jitter 0.5).

The discs cover pi / (2 sqrt(3)) = 90.7 % of the plane. The rest, 9.3 %, are the narrow holes
between three touching spheres: no sphere's cap lies over them, they reach down to the backstop
floor under the substrate (z = -d) and no powder sphere enters them. D is the mean over the covered
plane (the holes left out). ``mean_hollow_depth(jitter, hole_depth=1.0)`` gives the mean over the
whole plane with the holes at the backstop's depth instead: (pi / (2 sqrt 3)) D + (1 - pi / (2 sqrt 3)),
0.2443 d at jitter 0 and 0.3576 d at jitter 0.5 (tests/case/test_substrate.py checks both against a
Monte Carlo integral over an explicitly built lattice).

``floor_label`` names the floor and its gap for every map, table and report.
"""
from __future__ import annotations

import math

from ..schema import checked

FLAT, ROUGH = "flat", "rough"
COVERED = math.pi / (2.0 * math.sqrt(3.0))  # share of the plane under a sphere's cap (hexagonal layer)


def mean_hollow_depth(jitter: float, hole_depth: float | None = None) -> float:
    """Mean depth below z = 0 of the rough substrate's upper surface, in units of d.

    Averaged over the plane and over the random depths of its spheres (lowered by up to ``jitter``
    x R): D = 1/6 + jitter / 4 over the part of the plane the caps cover (see the module docstring).

    Parameters
    ----------
    jitter : float
        The largest depth a substrate sphere is lowered by, in radii R [-]; in [0, 1].
    hole_depth : float or None, optional
        None: the mean over the part of the plane the caps cover (the holes between three spheres,
        9.3 % of it, left out); a number: the mean over the whole plane with the holes at that
        depth (in d; 1.0: the backstop floor under the scene's substrate).

    Returns
    -------
    float
        The mean depth [d].

    Raises
    ------
    ValueError
        If ``jitter`` is outside [0, 1].
    """
    if not 0.0 <= jitter <= 1.0:
        raise ValueError(f"substrate jitter {jitter} outside [0, 1] (a depth in radii, up to one radius)")
    caps = 1.0 / 6.0 + jitter / 4.0
    return caps if hole_depth is None else COVERED * caps + (1.0 - COVERED) * float(hole_depth)


def hollow_depth(substrate, jitter) -> float:
    """The depth [d] an effective gap adds to h: 0 on a flat floor, ``mean_hollow_depth`` on a
    rough one; NaN where the floor (or a rough floor's jitter) is unknown."""
    if substrate == FLAT:
        return 0.0
    if substrate == ROUGH and jitter is not None and math.isfinite(float(jitter)):
        return mean_hollow_depth(float(jitter))
    return math.nan


def effective_gap_um(h_um: float, d_um: float, substrate, jitter) -> float:
    """The effective gap [um] of a case: h on a flat floor, h + the mean hollow depth on a rough one.

    Parameters
    ----------
    h_um : float
        The nominal gap h [um].
    d_um : float
        The particle diameter d [um].
    substrate : str
        The floor: "flat" or "rough" (anything else: unknown).
    jitter : float or None
        A rough floor's jitter [R]; None or NaN: unknown.

    Returns
    -------
    float
        h + D d [um], D the mean hollow depth (``mean_hollow_depth``; 0 on a flat floor); NaN
        where the floor (or a rough floor's jitter) is unknown.

    Raises
    ------
    ValueError
        If a rough floor's jitter is outside [0, 1].
    """
    return float(h_um) + hollow_depth(substrate, jitter) * float(d_um)


def floor_of(config: dict | None) -> tuple[str, float]:
    """(kind, jitter) of the floor a config's cases are spread on (``scene.substrate``, schema defaults).

    Parameters
    ----------
    config : dict or None
        The configuration; None, or one without ``scene.substrate``: the defaults.

    Returns
    -------
    kind : str
        "flat" or "rough" (as the config says; default: the schema's ``scene.substrate.kind``).
    jitter : float
        The rough floor's jitter [R] (default: the schema's ``scene.substrate.jitter``).
    """
    substrate = checked("scene.substrate", ((config or {}).get("scene") or {}).get("substrate"))
    return substrate["kind"], float(substrate["jitter"])


def floor_label(config: dict | None) -> str:
    """The floor and the gap a map, table or report is for, from the config.

    'flat floor; ...' or 'rough floor (previous layer, jitter 0.5 R); ...' with the effective gap in
    units of d.

    Parameters
    ----------
    config : dict or None
        The configuration the cases ran with (``scene.substrate``); None: the defaults (flat).

    Returns
    -------
    str
        The label, named on every map, table and report.

    Raises
    ------
    ValueError
        If ``scene.substrate.kind`` is neither "flat" nor "rough", or a rough floor's jitter is
        outside [0, 1].
    """
    kind, jitter = floor_of(config)
    if kind == FLAT:
        return "flat floor; gap h from the floor"
    if kind == ROUGH:
        return (f"rough floor (previous layer, jitter {jitter:g} R); gap h nominal, from its tops "
                f"(effective gap h + {mean_hollow_depth(jitter):.2f} d)")
    raise ValueError(f"config scene.substrate.kind {kind!r} is neither {FLAT!r} nor {ROUGH!r}")
