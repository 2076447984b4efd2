"""MFR and PD, the study's two axes, from the snapshots at the window's start and end.

MFR: volume (mass / density) that passed behind the blade's rear face during the measurement
     window, over the largest volume that could have passed: gap h x bed width W x blade travel.
     The volume is counted across the plane: each sphere contributes the exact volume of its part
     behind the face (a spherical cap when the face cuts it), plus the spheres removed earlier after
     rolling off the back end of the floor (whole: they were behind the blade).
PD:  solid fraction of the deposited layer at the end of the window in a box from the window
     start's blade rear face to a clearance behind the end's rear face (the material still in and
     just behind the gap is not yet a layer), full bed width, height h; spheres counted by their
     exact intersection volume with the box. The box must stay at least one blade thickness long.
Heap: the powder at or ahead of the blade's rear face (the heap the blade pushes and what lies
     under the blade), the exact part of each sphere ahead of the face, as a cross-section in h^2
     (volume / (W h^2)): what is left to feed the flow under the blade.
"""
from __future__ import annotations

import math

import numpy as np

from .geometry import sphere_box_volume, sphere_volume_below


def sphere_volume(diameter: float) -> float:
    return math.pi * diameter ** 3 / 6.0


def powder(snapshot: dict) -> tuple[np.ndarray, np.ndarray]:
    """Positions (n, 3) and radii (n,) of the spheres of a snapshot: the powder (a rough
    substrate's fixed spheres are recorded apart, in the raw record's `substrate`)."""
    return np.asarray(snapshot["positions"], float).reshape(-1, 3), np.asarray(snapshot["radii"], float)


def passed_volume(snapshot: dict) -> float:
    """Volume behind the blade's rear face at a snapshot: the part of every sphere with x below
    the face (exact caps), plus the volume removed earlier behind the blade."""
    positions, radii = powder(snapshot)
    behind = sphere_volume_below(positions[:, 0], radii, float(snapshot["blade_rear_x"]))
    return float(np.sum(behind)) + float(snapshot.get("removed_behind_volume", 0.0))


def heap_volume(snapshot: dict) -> float:
    """Volume at or ahead of the blade's rear face at a snapshot: the part of every sphere of the
    powder with x above the face (exact caps, the axis mirrored rather than the part behind taken
    from the whole sphere). A rough substrate is not in the snapshot (the raw record's
    `substrate`); the deposit, frozen or not, lies behind the face."""
    positions, radii = powder(snapshot)
    return float(np.sum(sphere_volume_below(-positions[:, 0], radii, -float(snapshot["blade_rear_x"]))))


def heap_h2(snapshot: dict, gap: float, width: float) -> float:
    """The heap ahead of the blade (heap_volume) as a cross-section in units of h^2: volume / (W h^2)."""
    return heap_volume(snapshot) / (width * gap * gap)


def window_passed_volume(start: dict, end: dict) -> float:
    """Volume that passed behind the blade between two snapshots."""
    return passed_volume(end) - passed_volume(start)


def mass_flow_ratio(start: dict, end: dict, gap: float, width: float) -> float:
    """MFR between two snapshots (dicts with positions, radii, blade_rear_x)."""
    travel = end["blade_rear_x"] - start["blade_rear_x"]
    if travel <= 0:
        raise ValueError("the blade did not advance during the measurement window")
    return window_passed_volume(start, end) / (gap * width * travel)


def measured_span(start: dict, end: dict, clearance: float, blade_thickness: float,
                  key: str = "metrics.pd_clearance_d", diameter: float | None = None) -> tuple[float, float]:
    """(x0, x1) of the deposited layer measured at the end of the window: from the window start's
    blade rear face to `clearance` behind the end's rear face. Refuses a span shorter than the
    blade thickness, naming the config key."""
    x0 = float(start["blade_rear_x"])
    x1 = float(end["blade_rear_x"]) - clearance
    if x1 - x0 < blade_thickness * (1.0 - 1e-9):
        unit, scale = ("d", diameter) if diameter else ("m", 1.0)
        raise ValueError(
            f"config key '{key}': a clearance of {clearance / scale:.3g} {unit} leaves a measured layer "
            f"{(x1 - x0) / scale:.3g} {unit} long (window travel {(end['blade_rear_x'] - x0) / scale:.3g} {unit}), "
            f"shorter than the blade thickness {blade_thickness / scale:.3g} {unit}; lower the clearance "
            f"or lengthen the window (it must be at least blade thickness + clearance)")
    return x0, x1


def layer_density(positions, radii, x0: float, x1: float, width: float, gap: float, slices: int = 1) -> np.ndarray:
    """Solid fraction in `slices` equal boxes along x between x0 and x1 (y in [0, W], z in [0, h])."""
    positions, radii = np.asarray(positions, float).reshape(-1, 3), np.asarray(radii, float)
    edges = np.linspace(x0, x1, slices + 1)
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        near = (positions[:, 0] > a - radii) & (positions[:, 0] < b + radii) & (positions[:, 2] < gap + radii)
        vol = sphere_box_volume(positions[near], radii[near], (a, 0.0, 0.0), (b, width, gap)).sum()
        out.append(vol / ((b - a) * width * gap))
    return np.array(out)
