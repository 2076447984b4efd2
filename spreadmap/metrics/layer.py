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
  volumes, spreadmap.metrics.geometry), and the measures decompose the study's box fraction exactly when
  the layer is below the gap: solid / (A h) = layer_fill x thickness_ratio.
What it means: voids under a sphere's overhang count as layer, bare floor does not. A single
layer of spheres resting on the floor whose shadows do not overlap (square or hexagonal
monolayer, a lone sphere) has layer_fill 4/5: solid (4/3) pi R^3 over the volume under its
dome, (5/3) pi R^3. Its gaps are in the coverage (pi/4 for a square monolayer of touching
spheres), not in the packing. A thick bed tends to its bulk packing.

Quantities (the mean runs over the floor area of the region, bare floor included)
- layer_fill = solid volume in the region / integral of s  (NaN without any powder),
- coverage      = share of the floor area with s > 0,
- roughness     = SD of s,
- thickness     = mean of s.
s is evaluated at the centres of a regular grid of cells (spacing `spacing`), so the integrals
are midpoint sums; their error comes from the circle rims: at a spacing of d/100 about 1e-3
relative in the worst case (a lattice in step with the grid, every rim cut the same way), less
for a random deposit (tests/metrics/test_layer.py).

Their noise (what another packing seed would change)
-----------------------------------------------------
Each measure is an average over the layer, so its noise is that of a spatial average: the
region is cut into B blocks of about `block` length along the travel (B = floor(length /
block), at least 2), each block's sums are kept (cells, sum s, sum s^2, cells with s > 0, solid
volume) and the measure's standard error is the delete-one-block jackknife's (Efron's
(B - 1) / B sum (theta_-j - theta_.)^2), which carries the ratio measures (packing) and the SD
(roughness) as well as the plain means. Neighbouring blocks share the spheres on their common
edge, so short blocks understate the error: on independent random deposits of known spread
(tests/metrics/test_layer.py) blocks of 1 d give 0.82-0.89 of it, blocks of 2 d 0.93-0.96 (the default,
metrics.layer_block_d). Against the SD over packing seeds of the same DEM design point
(docs/precision's 8 points x 4 seeds, 24 degrees of freedom per measure) blocks of 2 d give
0.72-1.25 of it (thickness lowest: part of its seed noise is the whole flow's, which one layer's
blocks cannot see; roughness highest). NaN with fewer than two blocks.
"""
from __future__ import annotations

import math

import numpy as np

from .geometry import sphere_box_volume


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


def _measures(cells: float, s_sum: float, s2_sum: float, covered: float, solid: float, cell_area: float) -> np.ndarray:
    """(layer_fill, coverage, roughness, thickness) from a region's sums over its grid cells."""
    mean = s_sum / cells
    packing = solid / (s_sum * cell_area) if s_sum > 0 else math.nan
    return np.array([packing, covered / cells, math.sqrt(max(s2_sum / cells - mean * mean, 0.0)), mean])


def block_standard_errors(sums: np.ndarray, cell_area: float) -> np.ndarray:
    """Delete-one-block jackknife SEs of (layer_fill, coverage, roughness, thickness) from the
    blocks' sums (B, 5: cells, sum s, sum s^2, cells with s > 0, solid volume); NaN if B < 2."""
    sums = np.asarray(sums, float)
    b = len(sums)
    if b < 2:
        return np.full(4, math.nan)
    total = sums.sum(axis=0)
    leave_out = np.array([_measures(*(total - row), cell_area) for row in sums])
    return np.sqrt((b - 1) / b * np.sum((leave_out - leave_out.mean(axis=0)) ** 2, axis=0))


def layer_quality(positions, radii, x0: float, x1: float, width: float, spacing: float,
                  block: float | None = None) -> dict:
    """Layer measures over [x0, x1] x [0, width] above z = 0 (SI units, see the module docstring):
    layer_fill, coverage, roughness (SD of s), thickness (mean of s), solid_volume, area; with
    `block` (a length), also each measure's block-jackknife standard error (`<measure>_sd`) and
    the number of blocks (`blocks`)."""
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
    out = {
        "layer_fill": solid / (thickness * area) if thickness > 0 else math.nan,
        "coverage": float(np.mean(s > 0.0)),
        "roughness": float(np.std(s)),
        "thickness": thickness,
        "solid_volume": solid,
        "area": area,
    }
    if block is not None:
        if not block > 0:
            raise ValueError(f"block length must be > 0, got {block}")
        n_blocks = int((x1 - x0) // block)
        sums = block_sums(s, xs, pos, rad, x0, x1, width, top, n_blocks) if n_blocks >= 2 else np.zeros((0, 5))
        se = block_standard_errors(sums, area / s.size)
        out.update({f"{name}_sd": float(v) for name, v in zip(("layer_fill", "coverage", "roughness", "thickness"), se)})
        out["blocks"] = n_blocks
    return out


def block_sums(s: np.ndarray, xs: np.ndarray, pos: np.ndarray, rad: np.ndarray, x0: float, x1: float,
               width: float, top: float, n_blocks: int) -> np.ndarray:
    """Per block of equal length along x: cells, sum s, sum s^2, cells with s > 0 and the solid
    volume inside the block's box (exact, spreadmap.metrics.geometry). Each grid column goes to the block
    holding its centre."""
    edges = np.linspace(x0, x1, n_blocks + 1)
    which = np.clip(np.searchsorted(edges, xs, side="right") - 1, 0, n_blocks - 1)
    rows = []
    for b in range(n_blocks):
        sb = s[which == b]
        inside = (pos[:, 0] + rad > edges[b]) & (pos[:, 0] - rad < edges[b + 1])
        solid = float(np.sum(sphere_box_volume(pos[inside], rad[inside], (edges[b], 0.0, 0.0),
                                               (edges[b + 1], width, top)))) if inside.any() else 0.0
        rows.append([sb.size, sb.sum(), np.sum(sb * sb), np.count_nonzero(sb > 0.0), solid])
    return np.array(rows, float)
