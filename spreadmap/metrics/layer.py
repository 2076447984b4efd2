"""Layer quality of the deposited layer: packing within its own thickness, coverage of the floor,
surface roughness and mean thickness, from one snapshot (the end of the measurement window).

The floor (or the top of a rough substrate) is the plane z = 0; the layer is measured over
x0 <= x <= x1 (from the window start's blade rear face to a clearance behind the end's) and the
full bed width 0 <= y <= W.

The surface
-----------
The local surface height s(x, y) is the upper envelope of the spheres seen from above,

    s(x, y) = max over spheres with r < R of  z_c + sqrt(R^2 - r^2),   r = |(x, y) - (x_c, y_c)|,

and s = 0 (the bare floor) where no sphere lies above the point. Why this one:
- it is what looks down on the layer: the laser, the next recoat and a profilometer meet this
  surface; where the floor shows, the layer thickness is zero and the laser melts the floor;
- it has no free parameter (a rolling-probe surface needs a probe radius, a smoothed one a
  length), and it is exact at every grid point;
- all solid above z = 0 lies below it, so the layer's solid volume is exact (sphere/box
  volumes, spreadmap.geometry), and the measures decompose the study's box fraction exactly when
  the layer is below the gap: solid / (A h) = layer_packing x thickness_ratio.
What it means: voids under a sphere's overhang count as layer, bare floor does not. A single
layer of spheres resting on the floor whose shadows do not overlap (square or hexagonal
monolayer, a lone sphere) has layer_packing 4/5: solid (4/3) pi R^3 over the volume under its
dome, (5/3) pi R^3. Its gaps are in the coverage (pi/4 for a square monolayer of touching
spheres), not in the packing. A thick bed tends to its bulk packing.

Quantities (the mean runs over the floor area of the region, bare floor included)
- layer_packing = solid volume in the region / integral of s  (NaN without any powder),
- coverage      = share of the floor area with s > 0,
- roughness     = SD of s,
- thickness     = mean of s.
s is evaluated at the centres of a regular grid of cells (spacing `spacing`), so the integrals
are midpoint sums; their error comes from the circle rims: at a spacing of d/100 about 1e-3
relative in the worst case (a lattice in step with the grid, every rim cut the same way), less
for a random deposit (tests/test_layer.py).
"""
from __future__ import annotations

import math

import numpy as np

from ..geometry import sphere_box_volume


def grid_centres(x0: float, x1: float, width: float, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres of a regular grid of cells covering [x0, x1] x [0, width], cells at most `spacing`
    wide (the counts are rounded up so that the cells tile the region exactly)."""
    if not (x1 > x0 and width > 0 and spacing > 0):
        raise ValueError(f"need x1 > x0, width > 0 and spacing > 0 (x0={x0}, x1={x1}, width={width}, spacing={spacing})")
    nx = max(1, math.ceil((x1 - x0) / spacing))
    ny = max(1, math.ceil(width / spacing))
    xs = x0 + (np.arange(nx) + 0.5) * (x1 - x0) / nx
    ys = (np.arange(ny) + 0.5) * width / ny
    return xs, ys


def upper_envelope(positions, radii, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """s(x, y) at the grid points xs (nx,) x ys (ny,): the highest point of any sphere above the
    point, 0 where no sphere is above it (and never below the floor z = 0)."""
    positions = np.asarray(positions, float).reshape(-1, 3)
    radii = np.broadcast_to(np.asarray(radii, float), (len(positions),))
    s = np.zeros((len(xs), len(ys)))
    for (xc, yc, zc), r in zip(positions, radii):
        i0, i1 = np.searchsorted(xs, [xc - r, xc + r])
        j0, j1 = np.searchsorted(ys, [yc - r, yc + r])
        if i0 >= i1 or j0 >= j1:
            continue
        r2 = r * r - (xs[i0:i1, None] - xc) ** 2 - (ys[None, j0:j1] - yc) ** 2
        top = np.where(r2 > 0.0, zc + np.sqrt(np.maximum(r2, 0.0)), 0.0)
        np.maximum(s[i0:i1, j0:j1], top, out=s[i0:i1, j0:j1])
    return s


def layer_quality(positions, radii, x0: float, x1: float, width: float, spacing: float) -> dict:
    """Layer measures over [x0, x1] x [0, width] above z = 0 (SI units, see the module docstring):
    layer_packing, coverage, roughness (SD of s), thickness (mean of s), solid_volume, area."""
    positions = np.asarray(positions, float).reshape(-1, 3)
    radii = np.broadcast_to(np.asarray(radii, float), (len(positions),))
    xs, ys = grid_centres(x0, x1, width, spacing)
    near = (positions[:, 0] + radii > x0) & (positions[:, 0] - radii < x1) & (positions[:, 2] + radii > 0.0)
    pos, rad = positions[near], radii[near]
    s = upper_envelope(pos, rad, xs, ys)
    area = (x1 - x0) * width
    top = float(np.max(pos[:, 2] + rad)) + 1.0 if len(pos) else 1.0
    solid = float(np.sum(sphere_box_volume(pos, rad, (x0, 0.0, 0.0), (x1, width, top)))) if len(pos) else 0.0
    thickness = float(np.mean(s))
    return {
        "layer_packing": solid / (thickness * area) if thickness > 0 else math.nan,
        "coverage": float(np.mean(s > 0.0)),
        "roughness": float(np.std(s)),
        "thickness": thickness,
        "solid_volume": solid,
        "area": area,
    }
