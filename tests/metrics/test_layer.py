"""Layer quality (spreadmap.metrics.layer) on constructed layers whose answers are worked out by
hand below, and on a random deposit checked by Monte Carlo with an independent point test
(scipy's cKDTree, not the grid code).

Hand values (sphere radius R, diameter d = 2R; surface s = upper envelope of the spheres, 0 on
bare floor). For one sphere resting on the floor, over its disc r < R:
  integral of s   = int (R + sqrt(R^2 - r^2)) 2 pi r dr = pi R^3 + 2/3 pi R^3 = 5/3 pi R^3,
  integral of s^2 = int (2 R^2 - r^2 + 2 R sqrt(R^2 - r^2)) 2 pi r dr = 3/2 pi R^4 + 4/3 pi R^4 = 17/6 pi R^4.
A monolayer whose discs do not overlap therefore has packing (4/3) / (5/3) = 4/5, whatever its
coverage; a cell of area A holding one sphere has coverage pi R^2 / A, mean s = 5/3 pi R^3 / A,
mean s^2 = 17/6 pi R^4 / A.
"""
import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from spreadmap.metrics.layer import grid_centres, layer_quality, upper_envelope

D = 1.0
R = 0.5 * D
SPACING = 0.01 * D  # the config's default grid (surface_grid_d)
GRID_REL = 2e-3  # midpoint-grid error at d/100 when every rim meets the grid the same way


def lattice(nx, ny, layers=1, x0=0.0, y0=0.0):
    """Simple cubic spheres of touching neighbours, centres at (x0 + (i + 1/2) d, y0 + (j + 1/2) d, (k + 1/2) d)."""
    return np.array([(x0 + (i + 0.5) * D, y0 + (j + 0.5) * D, (k + 0.5) * D)
                     for i in range(nx) for j in range(ny) for k in range(layers)])


def hand(cell_area, per_cell_spheres=1, extra_height=0.0):
    """coverage, mean thickness, roughness (SD) and packing of a layer with one dome of height
    extra_height + R + sqrt(R^2 - r^2) per cell (and per_cell_spheres spheres under it)."""
    a = extra_height + R  # flat part of the dome's height above the floor
    int_s = a * math.pi * R ** 2 + 2 / 3 * math.pi * R ** 3
    # int (a + sqrt(R^2 - r^2))^2 dA = a^2 pi R^2 + 2 a (2/3 pi R^3) + pi R^4 / 2
    int_s2 = a * a * math.pi * R ** 2 + 4 / 3 * a * math.pi * R ** 3 + 0.5 * math.pi * R ** 4
    mean = int_s / cell_area
    return {"coverage": math.pi * R ** 2 / cell_area, "thickness": mean,
            "roughness": math.sqrt(int_s2 / cell_area - mean ** 2),
            "layer_fill": per_cell_spheres * 4 / 3 * math.pi * R ** 3 / int_s}


def check(got, expected, rel=GRID_REL):
    for key, value in expected.items():
        assert got[key] == pytest.approx(value, rel=rel), (key, got[key], value)


def test_hand_formula_matches_the_quoted_integrals():
    h = hand(D * D)  # one sphere per d x d cell: the quoted 5/3, 17/6 integrals
    assert h["layer_fill"] == pytest.approx(0.8, rel=1e-15)
    assert h["thickness"] == pytest.approx(5 * math.pi / 24, rel=1e-15)
    assert h["roughness"] ** 2 == pytest.approx(17 * math.pi / 96 - 25 * math.pi ** 2 / 576, rel=1e-13)


def test_square_monolayer_of_touching_spheres():
    """Coverage pi/4, packing 4/5, thickness 5 pi d / 24, roughness sqrt(17 pi/96 - 25 pi^2/576) d."""
    got = layer_quality(lattice(10, 4), R, 0.0, 10 * D, 4 * D, SPACING)
    check(got, {"coverage": math.pi / 4, "layer_fill": 0.8, "thickness": 5 * math.pi / 24 * D,
                "roughness": math.sqrt(17 * math.pi / 96 - 25 * math.pi ** 2 / 576) * D})
    assert got["solid_volume"] == pytest.approx(40 * 4 / 3 * math.pi * R ** 3, rel=1e-13)  # exact, not gridded


def test_region_cutting_through_spheres_keeps_the_cell_averages():
    """A region of whole periods that starts mid-sphere: spheres cut by its ends count by their
    exact part inside (sphere/box volumes); the averages stay the lattice's."""
    got = layer_quality(lattice(14, 4), R, 2.3 * D, 12.3 * D, 4 * D, SPACING)
    check(got, hand(D * D))


def test_two_layers_simple_cubic():
    """The envelope is the top layer's domes at height 2R above the first: packing 8/11."""
    got = layer_quality(lattice(10, 4, layers=2), R, 0.0, 10 * D, 4 * D, SPACING)
    expected = hand(D * D, per_cell_spheres=2, extra_height=D)
    assert expected["layer_fill"] == pytest.approx(8 / 11, rel=1e-15)
    check(got, expected)


def test_half_covered_floor():
    """A square monolayer over the first half, bare floor over the second: coverage pi/8, half
    the thickness, the same packing (bare floor is not layer)."""
    got = layer_quality(lattice(6, 4), R, 0.0, 12 * D, 4 * D, SPACING)
    expected = hand(2 * D * D)  # one sphere per 2 d^2 of floor on average
    assert expected["coverage"] == pytest.approx(math.pi / 8)
    check(got, expected)


def test_fully_covered_half_floor_is_coverage_one_half():
    """Overlapping spheres on a square grid of spacing R/2 (< R sqrt 2: no floor point between
    them is uncovered), centres over x in [R, 5 d - R], y in [0, 4 d], in a region [0, 10 d] x
    [0, 4 d]: the shadow is the first half of the floor but for shallow scallops between the
    rows at its two ends (depth ~ u^2 / 2R: (R/2)^3 / (24 R) of area per row gap and end, 1.0e-3
    of the floor in all: coverage 0.499); also against a Monte Carlo estimate of the union of discs."""
    xs = np.arange(R, 5 * D - R + 1e-9, 0.5 * R)
    ys = np.arange(0.0, 4 * D + 1e-9, 0.5 * R)
    pos = np.array([(x, y, R) for x in xs for y in ys])
    got = layer_quality(pos, R, 0.0, 10 * D, 4 * D, SPACING)
    scallops = 2 * (len(ys) - 1) * (0.5 * R) ** 3 / (24 * R) / (40 * D * D)
    assert got["coverage"] == pytest.approx(0.5 - scallops, abs=2e-4)
    rng = np.random.default_rng(0)
    pts = rng.uniform((0, 0), (10 * D, 4 * D), size=(200_000, 2))
    share = np.mean(cKDTree(pos[:, :2]).query(pts, distance_upper_bound=R)[0] < R)
    assert abs(got["coverage"] - share) < 4 * math.sqrt(share * (1 - share) / len(pts)) + 1e-3


def test_single_row_of_spheres():
    """One row along x in the middle of a 4 d wide bed: per d x 4 d cell one sphere: coverage
    pi/16, thickness 5 pi d/96, roughness sqrt(17 pi/384 - (5 pi/96)^2) d, packing 4/5."""
    pos = np.array([((i + 0.5) * D, 2.0 * D, R) for i in range(10)])
    got = layer_quality(pos, R, 0.0, 10 * D, 4 * D, SPACING)
    expected = {"coverage": math.pi / 16, "thickness": 5 * math.pi / 96 * D, "layer_fill": 0.8,
                "roughness": math.sqrt(17 * math.pi / 384 - (5 * math.pi / 96) ** 2) * D}
    check(got, expected)
    check(hand(4 * D * D), expected, rel=1e-13)  # the two hand routes agree


def test_hemisphere_sunk_in_the_substrate_fills_its_dome():
    """A sphere centred on z = 0 (half below the plane of a rough substrate's top): the solid above
    z = 0 is (2/3) pi R^3, exactly the volume under its dome: packing 1."""
    got = layer_quality([[2.0, 2.0, 0.0]], R, 0.0, 4 * D, 4 * D, SPACING)
    assert got["solid_volume"] == pytest.approx(2 / 3 * math.pi * R ** 3, rel=1e-13)
    assert got["layer_fill"] == pytest.approx(1.0, rel=GRID_REL)


def test_empty_region_and_spheres_outside_it():
    got = layer_quality([[20.0, 2.0, R], [-3.0, 1.0, R]], R, 0.0, 10 * D, 4 * D, SPACING)
    assert got["coverage"] == 0.0 and got["thickness"] == 0.0 and got["roughness"] == 0.0
    assert math.isnan(got["layer_fill"]) and got["solid_volume"] == 0.0
    empty = layer_quality(np.zeros((0, 3)), R, 0.0, 10 * D, 4 * D, SPACING)
    assert empty["coverage"] == 0.0 and math.isnan(empty["layer_fill"])


def test_grid_is_refused_when_degenerate():
    with pytest.raises(ValueError, match="x1 > x0"):
        grid_centres(1.0, 1.0, 4.0, 0.01)


def random_deposit(n, length, width, rng):
    """Ballistic deposit: each sphere falls at a random (x, y) and stops on the floor or on the
    first sphere it meets (no rolling): a porous, rough multi-layer."""
    out = []
    for _ in range(n):
        x, y = rng.uniform((0.0, 0.0), (length, width))
        z = R
        for (xc, yc, zc) in out:
            r2 = (x - xc) ** 2 + (y - yc) ** 2
            if r2 < D * D:
                z = max(z, zc + math.sqrt(D * D - r2))
        out.append((x, y, z))
    return np.array(out)


def test_random_deposit_against_monte_carlo():
    """Coverage, mean thickness and packing of a random deposit against a Monte Carlo estimate
    whose point tests use a KD tree (not the grid): a floor point is covered if a sphere centre
    lies within R horizontally; a point (x, y, z) is below the surface if z < z_c + sqrt(R^2 - r^2)
    for such a sphere; solid if within R of a centre."""
    rng = np.random.default_rng(11)
    length, width = 8.0 * D, 4.0 * D
    pos = random_deposit(45, length, width, rng)
    got = layer_quality(pos, R, 0.0, length, width, SPACING)
    assert 0.3 < got["coverage"] < 0.95 and 0.3 < got["layer_fill"] < 0.8  # a non-trivial layer
    n = 300_000
    top = pos[:, 2].max() + R
    p = rng.uniform((0, 0, 0), (length, width, top), size=(n, 3))
    dist, idx = cKDTree(pos[:, :2]).query(p[:, :2], k=12, distance_upper_bound=R)
    hit = dist < R
    s = np.where(hit, pos[np.minimum(idx, len(pos) - 1), 2] + np.sqrt(np.maximum(R * R - dist ** 2, 0.0)), 0.0).max(axis=1)
    below = p[:, 2] < s
    solid = cKDTree(pos).query(p, distance_upper_bound=R)[0] < R
    assert not np.any(solid & ~below)  # the envelope is above all solid
    cover = hit.any(axis=1)
    se = lambda q, m: math.sqrt(q * (1 - q) / m)  # noqa: E731
    q = cover.mean()
    assert abs(got["coverage"] - q) < 4 * se(q, n) + 1e-3
    q = below.mean()  # share of the box under the surface = mean thickness / box height
    assert abs(got["thickness"] / top - q) < 4 * se(q, n) + 1e-3
    q = solid.sum() / below.sum()
    assert abs(got["layer_fill"] - q) < 4 * se(q, below.sum()) + 1e-3
    # mean of s^2 from the same floor points: roughness
    mean, mean2 = s.mean(), (s ** 2).mean()
    sd_mc = math.sqrt(mean2 - mean ** 2)
    assert got["roughness"] == pytest.approx(sd_mc, rel=0.02)


def test_envelope_takes_the_highest_sphere():
    xs, ys = np.array([0.0, 0.3]), np.array([0.0])
    s = upper_envelope([[0.0, 0.0, R], [0.0, 0.0, 3 * R]], R, xs, ys)
    np.testing.assert_allclose(s[:, 0], [4 * R, 3 * R + math.sqrt(R * R - 0.09)])


# The layer measures' noise: block jackknife standard errors (layer_quality(..., block=...))

MEASURES = ("layer_fill", "coverage", "roughness", "thickness")


def test_block_errors_match_the_spread_over_independent_deposits():
    """The known truth: 300 independent random deposits (Poisson number of spheres, uniform in x
    and y, lifted by up to one diameter) of one design; the SD of each measure over them is what a
    single deposit's standard error must state. Blocks of 2 d give 0.93-0.96 of it for this
    seed (the shared edge spheres make neighbouring blocks correlate: 1 d blocks give ~0.85)."""
    rng = np.random.default_rng(5)
    length, width = 16 * D, 4 * D
    values, errors = [], []
    for _ in range(300):
        n = rng.poisson(length * width / D ** 2)
        pos = np.column_stack([rng.uniform(-R, length + R, n), rng.uniform(0, width, n), R + rng.uniform(0, D, n)])
        got = layer_quality(pos, R, 0.0, length, width, D / 10, block=2 * D)
        assert got["blocks"] == 8
        values.append([got[m] for m in MEASURES])
        errors.append([got[m + "_sd"] for m in MEASURES])
    spread = np.std(values, axis=0, ddof=1)
    stated = np.sqrt(np.mean(np.square(errors), axis=0))
    # the SD of an SD from 300 draws is ~4 %: 0.85-1.10 allows the known ~5 % understatement
    assert np.all((stated / spread > 0.85) & (stated / spread < 1.10)), dict(zip(MEASURES, stated / spread))


def test_block_errors_vanish_on_a_periodic_layer_and_need_two_blocks():
    """A simple cubic monolayer whose period divides the block: every block is the same, so no
    block-to-block variation and zero error; one block cannot state an error (NaN); the measures
    themselves do not depend on whether the errors are asked for."""
    pos = lattice(12, 4)
    got = layer_quality(pos, R, 0.0, 12 * D, 4 * D, D / 50, block=2 * D)
    assert got["blocks"] == 6
    for m in MEASURES:
        assert got[m + "_sd"] == pytest.approx(0.0, abs=1e-9), m
    plain = layer_quality(pos, R, 0.0, 12 * D, 4 * D, D / 50)
    assert all(got[m] == plain[m] for m in MEASURES) and "blocks" not in plain
    short = layer_quality(pos, R, 0.0, 12 * D, 4 * D, D / 50, block=7 * D)
    assert short["blocks"] == 1 and all(math.isnan(short[m + "_sd"]) for m in MEASURES)
    with pytest.raises(ValueError, match="block length"):
        layer_quality(pos, R, 0.0, 12 * D, 4 * D, D / 50, block=0.0)


def test_block_error_of_coverage_against_the_binomial_of_independent_blocks():
    """An independent number: 10 blocks of 2 d, each either a 2 x 4 square of touching spheres
    (coverage pi/4) or bare, at random. Coverage = (share p of covered blocks) x pi/4, and the
    jackknife SE of a mean of B block values is the textbook sqrt(sum (x_b - mean)^2 / (B (B - 1))),
    here sqrt(p (1 - p) / (B - 1)) x pi/4."""
    rng = np.random.default_rng(3)
    full = rng.random(10) < 0.5
    full[:2] = [True, False]  # both kinds present
    pos = np.vstack([lattice(2, 4, x0=2 * D * b) for b in range(10) if full[b]])
    got = layer_quality(pos, R, 0.0, 20 * D, 4 * D, D / 100, block=2 * D)
    p = full.mean()
    assert got["coverage"] == pytest.approx(p * math.pi / 4, rel=GRID_REL)
    assert got["coverage_sd"] == pytest.approx(math.sqrt(p * (1 - p) / 9) * math.pi / 4, rel=5e-3)


def close_packed(nx, rows, layers):
    """Face-centred cubic spheres stacked ABC along z (close-packed layers, layer spacing d sqrt(2/3)),
    over a region nx d long and rows d sqrt(3) wide (whole periods of the layer), with a margin of
    spheres beyond the region so that the surface and the solid inside it are the lattice's."""
    c, width = D * math.sqrt(2.0 / 3.0), rows * D * math.sqrt(3.0)
    offsets = [(0.0, 0.0), (D / 2, D * math.sqrt(3.0) / 6), (D, D * math.sqrt(3.0) / 3)]
    centres = []
    for k in range(layers):
        ox, oy = offsets[k % 3]
        for j in range(-3, 2 * rows + 4):
            for i in range(-3, nx + 4):
                x, y = ox + i * D + (j % 2) * D / 2, oy + j * D * math.sqrt(3.0) / 2
                if -D <= x <= (nx + 1) * D and -D <= y <= width + D:
                    centres.append((x, y, R + k * c))
    return np.array(centres), width


def test_close_packed_layers_against_the_known_packing_fraction():
    """A thick bed of known packing: every close-packed layer added to an FCC stack adds its solid
    and raises the surface by one layer spacing, so the added solid over the added volume under the
    surface is the FCC fraction pi / (3 sqrt 2) = 0.7405 (a number from geometry, not from this code).
    The layer fill of the whole stack starts at the monolayer's 4/5 and falls towards 0.7405 as the
    bed thickens: it is a volume fraction of the region under the surface, not a bulk packing fraction."""
    fcc = math.pi / (3.0 * math.sqrt(2.0))
    got = {}
    for n in (1, 4, 6):
        centres, width = close_packed(4, 2, n)
        got[n] = layer_quality(centres, R, 0.0, 4 * D, width, SPACING)
    # one close-packed layer: coverage pi / (2 sqrt 3), fill 4/5 (its shadows touch, never overlap)
    assert got[1]["coverage"] == pytest.approx(math.pi / (2.0 * math.sqrt(3.0)), rel=GRID_REL)
    assert got[1]["layer_fill"] == pytest.approx(0.8, rel=GRID_REL)
    added_solid = got[6]["solid_volume"] - got[4]["solid_volume"]
    added_volume = (got[6]["thickness"] - got[4]["thickness"]) * got[6]["area"]
    # 16 spheres a layer: the area 4 d x 2 sqrt(3) d at 2 / (sqrt(3) d^2) spheres per area
    assert added_solid == pytest.approx(2 * 16 * (4 / 3) * math.pi * R ** 3, rel=1e-9)
    assert added_solid / added_volume == pytest.approx(fcc, rel=GRID_REL)
    assert 0.8 > got[4]["layer_fill"] > got[6]["layer_fill"] > fcc
