"""The powder model a case simulates, beyond its design point: dry spheres, or spheres with DMT
adhesion (config ``material.surface_energy_j_m2``), and the granular Bond number that says how much
the adhesion weighs against gravity.

YADE's Hertz-Mindlin law applies a pull-off force 4 pi gamma R* (R* = R/2 for two equal spheres;
measured in tests/case/test_adhesion_yade.py), so a pair of spheres of diameter d and density rho
has the Bond number (pull-off / one sphere's weight) 4 pi gamma (d/4) / (rho g pi d^3 / 6) =
6 gamma / (rho g d^2). ``powder_label`` names the model on every map, table and report, beside the
floor (rules/common.smk).
"""
from __future__ import annotations


def bond_number(surface_energy: float, density: float, gravity: float, diameter: float) -> float:
    """The granular Bond number of two equal spheres: DMT pull-off over one sphere's weight.

    Parameters
    ----------
    surface_energy : float
        The real powder's surface energy gamma [J/m^2].
    density : float
        The real solid density [kg/m^3] (density scaling multiplies weight and adhesion alike).
    gravity : float
        Gravity [m/s^2].
    diameter : float
        The sphere diameter [m].

    Returns
    -------
    float
        6 gamma / (rho g d^2) [-].
    """
    return 6.0 * surface_energy / (density * gravity * diameter ** 2)


def powder_label(config: dict) -> str:
    """The powder model a map, table or report is for, from the config.

    Parameters
    ----------
    config : dict
        The configuration the cases ran with (``material``, ``ranges.d_um``); a material without
        ``surface_energy_j_m2`` is dry (the schema's default, 0).

    Returns
    -------
    str
        'dry spheres (no adhesion)' or 'adhesive spheres (DMT, surface energy 0.1 mJ/m^2; Bond number
        77 at d = 10 um to 3.1 at 50 um)', followed for a size distribution (span > 0) by
        ', sizes log-normal by volume (span 1, cut at D1-D99; d is the D50)'.
    """
    material = config["material"]
    return _adhesion_label(config) + _size_label(material.get("size_distribution") or {})


def _adhesion_label(config: dict) -> str:
    material = config["material"]
    gamma = float(material.get("surface_energy_j_m2", 0.0))
    if gamma <= 0.0:
        return "dry spheres (no adhesion)"
    d_range = (config.get("ranges") or {}).get("d_um") or {"min": 10.0, "max": 50.0}

    def bond(d_um: float) -> float:
        return bond_number(gamma, material["density_kg_m3"], material["gravity_m_s2"], d_um * 1e-6)

    return (f"adhesive spheres (DMT, surface energy {gamma * 1e3:.3g} mJ/m^2; Bond number "
            f"{bond(d_range['min']):.2g} at d = {d_range['min']:g} um to {bond(d_range['max']):.2g} at {d_range['max']:g} um)")


def _size_label(sizes: dict) -> str:
    """'' for spheres of one size (a config without a size distribution, or span 0); else the
    distribution, d being its D50."""
    span = float(sizes.get("span", 0.0))
    if span == 0.0:
        return ""
    low, high = sizes["tails"]
    return (f", sizes log-normal by volume (span {span:g}, cut at D{low * 100:g}-D{high * 100:g}; "
            f"d is the D50)")
