"""Tests of spreadmap.metrics.geometry: exact sphere/box intersection volumes and solid fractions.

Every expected value is independent of the implementation (a closed-form octant expansion):
textbook volumes (ball, cap, slab, symmetric fractions), Monte Carlo estimates, a 2-D midpoint
grid over exact chord lengths, and an adaptive 1-D quadrature (scipy) over height of the
disc/rectangle slice area, which is itself computed by integrating chord lengths piecewise.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.integrate import quad

from spreadmap.metrics.geometry import _general_volume, cap_volume, solid_fraction, sphere_box_volume, sphere_volume_below

BALL = 4.0 * np.pi / 3.0


def ball(r):
    return BALL * r ** 3


def cap(r, h):
    """Volume of a spherical cap of height h (0 <= h <= 2r)."""
    return np.pi * h * h * (3.0 * r - h) / 3.0


def slab(r, z1, z2):
    """Volume of the part of a ball (centre 0, radius r) with z1 < z < z2 (|z1|, |z2| <= r)."""
    prim = lambda z: np.pi * (r * r * z - z ** 3 / 3.0)  # noqa: E731
    return prim(z2) - prim(z1)


# --------------------------------------------------------------------------------------------
# Independent references
# --------------------------------------------------------------------------------------------
def _disc_rect_area(rho, x0, x1, y0, y1):
    """Area of the disc (centre 0, radius rho) ∩ [x0, x1] x [y0, y1].

    Integrates the vertical chord length over x piecewise: between the x-values where the circle
    crosses y = y0 or y = y1, each chord end is either the circle or a rectangle edge, and
    int sqrt(rho^2 - x^2) dx = (x sqrt(rho^2 - x^2) + rho^2 asin(x / rho)) / 2.
    """
    if rho <= 0.0:
        return 0.0
    xl, xr = max(x0, -rho), min(x1, rho)
    if xl >= xr:
        return 0.0

    def prim(x):
        return 0.5 * (x * np.sqrt(max(rho * rho - x * x, 0.0)) + rho * rho * np.arcsin(np.clip(x / rho, -1, 1)))

    cuts = {xl, xr}
    for y in (y0, y1):
        if abs(y) < rho:
            q = np.sqrt(rho * rho - y * y)
            cuts |= {q, -q}
    cuts = sorted(p for p in cuts if xl <= p <= xr)
    area = 0.0
    for p, q in zip(cuts[:-1], cuts[1:]):
        if q <= p:
            continue
        m = 0.5 * (p + q)
        s = np.sqrt(rho * rho - m * m)
        if min(y1, s) <= max(y0, -s):
            continue  # chord misses the rectangle on this piece
        circle_arc = prim(q) - prim(p)
        top = circle_arc if s < y1 else y1 * (q - p)
        bottom = -circle_arc if -s > y0 else y0 * (q - p)
        area += top - bottom
    return area


def quad_volume(centre, r, lo, hi):
    """Sphere/box volume by adaptive quadrature over z of the exact slice area, with the kinks
    (slice radius = distance from the axis to an edge line or a corner) as breakpoints."""
    c = np.asarray(centre, float)
    lo = np.asarray(lo, float) - c
    hi = np.asarray(hi, float) - c
    zl, zh = max(lo[2], -r), min(hi[2], r)
    if zl >= zh:
        return 0.0
    kinks = [np.sqrt(r * r - d * d) for d in (lo[0], hi[0], lo[1], hi[1]) if abs(d) < r]
    kinks += [np.sqrt(r * r - dx * dx - dy * dy) for dx in (lo[0], hi[0]) for dy in (lo[1], hi[1])
              if dx * dx + dy * dy < r * r]
    pts = sorted({s * k for k in kinks for s in (1.0, -1.0) if zl < s * k < zh} | {zl, zh})

    def area(z):
        return _disc_rect_area(np.sqrt(max(r * r - z * z, 0.0)), lo[0], hi[0], lo[1], hi[1])

    total = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for p, q in zip(pts[:-1], pts[1:]):
            total += quad(area, p, q, epsabs=0.0, epsrel=1e-12, limit=200)[0]
    return total


def monte_carlo_volume(centre, r, lo, hi, n, rng):
    """Monte Carlo estimate (and its standard error) of the sphere/box volume, sampling
    uniformly in the box clipped to the sphere's bounding cube."""
    c = np.asarray(centre, float)
    a = np.maximum(np.asarray(lo, float), c - r)
    b = np.minimum(np.asarray(hi, float), c + r)
    v_sample = float(np.prod(b - a))
    hits = 0
    for _ in range(n // 500_000):
        p = rng.uniform(a, b, size=(500_000, 3))
        hits += int(np.count_nonzero(np.sum((p - c) ** 2, axis=1) < r * r))
    frac = hits / n
    return v_sample * frac, v_sample * np.sqrt(frac * (1.0 - frac) / n)


def grid_volume(centre, r, lo, hi, m=1500):
    """Brute force: m x m midpoint grid over (x, y) of the exact z-chord length of the ball
    clipped to [lo_z, hi_z]."""
    c = np.asarray(centre, float)
    lo = np.asarray(lo, float)
    hi = np.asarray(hi, float)
    x = lo[0] + (np.arange(m) + 0.5) * (hi[0] - lo[0]) / m
    y = lo[1] + (np.arange(m) + 0.5) * (hi[1] - lo[1]) / m
    dx2 = (x - c[0])[:, None] ** 2 + (y - c[1])[None, :] ** 2
    half = np.sqrt(np.maximum(r * r - dx2, 0.0))
    chord = np.clip(np.minimum(c[2] + half, hi[2]) - np.maximum(c[2] - half, lo[2]), 0.0, None)
    return float(chord.sum()) * (hi[0] - lo[0]) * (hi[1] - lo[1]) / m ** 2


def one(centre, r, lo, hi):
    return float(sphere_box_volume(np.asarray([centre], float), r, lo, hi)[0])


def general(centre, r, lo, hi):
    """The multi-face closed form on its own (bypassing the fast paths)."""
    c = np.asarray([centre], float)
    return float(_general_volume(np.asarray(lo, float) - c, np.asarray(hi, float) - c, np.array([float(r)]))[0])


# --------------------------------------------------------------------------------------------
# Inside / outside / tangent
# --------------------------------------------------------------------------------------------
def test_fully_inside_is_ball_volume():
    centres = np.array([[0.0, 0.0, 0.0], [1.0, -2.0, 0.5], [2.9, 2.9, 2.9], [-2.5, 0.0, 1.0]])
    radii = np.array([1.0, 0.3, 0.1, 0.5])
    v = sphere_box_volume(centres, radii, (-3, -3, -3), (3, 3, 3))
    np.testing.assert_allclose(v, BALL * radii ** 3, rtol=1e-14)
    # tangent to the box from the inside: still whole
    assert one((0.0, 0.0, 2.0), 1.0, (-3, -3, -3), (3, 3, 3)) == pytest.approx(ball(1.0), rel=1e-14)


def test_fully_outside_and_tangent_from_outside_are_zero():
    lo, hi = (0.0, 0.0, 0.0), (10.0, 10.0, 10.0)
    centres = np.array([
        [-5.0, 5.0, 5.0],  # clear of the x = 0 face
        [15.0, 15.0, 15.0],  # beyond a corner
        [-1.0, 5.0, 5.0],  # tangent to the face x = 0 (r = 1)
        [-3.0, -4.0, 5.0],  # tangent to the edge x = y = 0 (distance 5, r = 5)
        [-2.0, -3.0, -6.0],  # tangent to the corner (distance 7, r = 7)
        [-3.0, -3.0, 5.0],  # near the edge, diagonal gap sqrt(18) > r = 4.2
    ])
    radii = np.array([1.0, 2.0, 1.0, 5.0, 7.0, 4.2])
    np.testing.assert_array_equal(sphere_box_volume(centres, radii, lo, hi), np.zeros(6))
    # the closed form alone gives 0 too (beyond rounding)
    for c, r in zip(centres, radii):
        assert abs(general(c, r, lo, hi)) <= 1e-15 * ball(r)


def test_zero_radius_and_empty_input():
    assert one((0.5, 0.5, 0.5), 0.0, (0, 0, 0), (1, 1, 1)) == 0.0
    v = sphere_box_volume(np.zeros((0, 3)), np.zeros(0), (0, 0, 0), (1, 1, 1))
    assert v.shape == (0,)
    assert solid_fraction(np.zeros((0, 3)), 1.0, (0, 0, 0), (1, 1, 1)) == 0.0


# --------------------------------------------------------------------------------------------
# One plane: spherical caps
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("h_over_r", [1e-6, 0.05, 0.3, 0.5, 1.0, 1.37, 1.9, 2.0 - 1e-6])
def test_one_plane_cap_on_every_face(h_over_r):
    r = 0.7
    h = h_over_r * r
    lo, hi = np.array([-5.0, -4.0, -3.0]), np.array([5.0, 4.0, 3.0])
    expected = cap(r, h)
    for axis in range(3):
        for side in (0, 1):
            c = np.zeros(3)
            # the part of the ball inside the box has height h
            c[axis] = lo[axis] + h - r if side == 0 else hi[axis] - h + r
            got = one(c, r, lo, hi)
            assert got == pytest.approx(expected, rel=1e-12, abs=1e-15 * ball(r))
            assert general(c, r, lo, hi) == pytest.approx(expected, rel=1e-9, abs=1e-15 * ball(r))


def test_centre_on_a_face_is_half():
    r = 1.3
    lo, hi = (0.0, -5.0, -5.0), (5.0, 5.0, 5.0)
    assert one((0.0, 0.2, -0.4), r, lo, hi) == pytest.approx(0.5 * ball(r), rel=1e-14)
    assert general((0.0, 0.2, -0.4), r, lo, hi) == pytest.approx(0.5 * ball(r), rel=1e-14)


# --------------------------------------------------------------------------------------------
# Symmetric multi-plane cuts and slabs (analytic)
# --------------------------------------------------------------------------------------------
def test_two_perpendicular_planes_through_centre_is_quarter():
    r = 0.9
    big = 10.0
    for sx in (-1, 1):
        for sy in (-1, 1):
            lo = (min(0, sx * big), min(0, sy * big), -big)
            hi = (max(0, sx * big), max(0, sy * big), big)
            assert one((0, 0, 0), r, lo, hi) == pytest.approx(0.25 * ball(r), rel=1e-14)
    # same with the edge along x, centre elsewhere
    assert one((3.0, 1.0, 2.0), r, (-big, 1.0, 2.0), (big, big, big)) == pytest.approx(0.25 * ball(r), rel=1e-14)


def test_three_planes_through_centre_is_eighth():
    r = 2.1
    big = 10.0
    for s in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).T.reshape(-1, 3):
        lo = np.minimum(0, s * big)
        hi = np.maximum(0, s * big)
        assert one((0, 0, 0), r, lo, hi) == pytest.approx(ball(r) / 8, rel=1e-14)
    c = (0.25, -1.5, 4.0)
    assert one(c, r, c, (big, big, big)) == pytest.approx(ball(r) / 8, rel=1e-14)


@pytest.mark.parametrize("t_over_r", [1e-3, 0.1, 0.45, 0.8, 0.999])
def test_centred_thin_slab(t_over_r):
    r = 1.7
    t = t_over_r * r
    expected = slab(r, -t, t)  # = 2 pi (r^2 t - t^3 / 3)
    for axis in range(3):
        lo, hi = np.full(3, -10.0), np.full(3, 10.0)
        lo[axis], hi[axis] = -t, t
        assert one((0, 0, 0), r, lo, hi) == pytest.approx(expected, rel=1e-12)


def test_off_centre_slab_and_quarter_slab():
    r = 1.0
    z1, z2 = -0.35, 0.62
    expected = slab(r, z1, z2)
    assert one((0, 0, 0), r, (-3, -3, z1), (3, 3, z2)) == pytest.approx(expected, rel=1e-13)
    # plus two perpendicular planes through the axis: a quarter of the slab (4 faces cut)
    assert one((0, 0, 0), r, (0, 0, z1), (3, 3, z2)) == pytest.approx(expected / 4, rel=1e-13)
    assert one((0, 0, 0), r, (-3, 0, z1), (0, 3, z2)) == pytest.approx(expected / 4, rel=1e-13)


def test_box_inside_sphere_is_box_volume():
    lo, hi = (-0.3, -0.2, -0.1), (0.4, 0.25, 0.5)
    box = 0.7 * 0.45 * 0.6
    assert one((0.01, 0.02, 0.03), 5.0, lo, hi) == pytest.approx(box, rel=1e-14)
    # a box whose far corner lies exactly on the sphere
    assert one((0, 0, 0), 3.0, (-1, -2, -2), (1, 2, 2)) == pytest.approx(32.0, rel=1e-14)
    assert general((0, 0, 0), 3.0, (-1, -2, -2), (1, 2, 2)) == pytest.approx(32.0, rel=1e-9)
    assert general((0.01, 0.02, 0.03), 5.0, lo, hi) == pytest.approx(box, rel=1e-9)


# --------------------------------------------------------------------------------------------
# Off-centre cuts: Monte Carlo, brute-force grid, adaptive quadrature
# --------------------------------------------------------------------------------------------
OFF_CENTRE_CASES = [
    # (centre, r, lo, hi, number of faces cut)
    ((0.3, -0.2, 0.0), 1.0, (-0.1, -0.5, -5.0), (5.0, 5.0, 5.0), 2),
    ((0.0, 0.0, 0.0), 1.0, (0.45, -0.7, -5.0), (5.0, 0.2, 5.0), 3),
    ((0.2, 0.1, -0.3), 1.0, (-0.4, -0.6, -0.1), (5.0, 5.0, 5.0), 3),
    ((1.1, 2.2, 0.7), 0.8, (0.6, 1.9, 0.0), (1.5, 5.0, 1.2), 5),
    ((0.0, 0.0, 0.0), 2.0, (-1.5, -1.2, -1.0), (1.0, 1.3, 1.6), 6),  # sphere larger than box
]


@pytest.mark.parametrize("case", OFF_CENTRE_CASES, ids=lambda c: f"{c[4]}faces")
def test_off_centre_against_monte_carlo(case):
    centre, r, lo, hi, _ = case
    got = one(centre, r, lo, hi)
    est, se = monte_carlo_volume(centre, r, lo, hi, 2_000_000, np.random.default_rng(20240611))
    assert se > 0
    assert abs(got - est) <= 4.0 * se, (got, est, se)


@pytest.mark.parametrize("case", OFF_CENTRE_CASES, ids=lambda c: f"{c[4]}faces")
def test_off_centre_against_quadrature(case):
    centre, r, lo, hi, _ = case
    assert one(centre, r, lo, hi) == pytest.approx(quad_volume(centre, r, lo, hi), rel=1e-10)


def test_three_planes_against_midpoint_grid():
    centre, r, lo, hi, _ = OFF_CENTRE_CASES[2]
    assert one(centre, r, lo, hi) == pytest.approx(grid_volume(centre, r, lo, hi), rel=1e-4)


def test_random_multi_face_cases_against_quadrature():
    """Boxes of the size of the sphere, placed to cut it by 2 to 6 faces, including degenerate
    placements (faces through the centre, corners on the sphere surface)."""
    rng = np.random.default_rng(7)
    r = 1.0
    special = np.array([0.0, 0.5, -0.5, 1.0, -1.0, np.sqrt(0.5), -np.sqrt(0.5), 1e-9])
    worst = 0.0
    for k in range(40):
        lo = rng.choice(special, 3) if k % 2 else rng.uniform(-1.2, 0.9, 3)
        hi = lo + (rng.choice([0.3, 1.0, 1.6, 1.0 - np.sqrt(0.5)], 3) if k % 3 else rng.uniform(0.05, 2.0, 3))
        got = one((0, 0, 0), r, lo, hi)
        ref = quad_volume((0, 0, 0), r, lo, hi)
        err = abs(got - ref)
        assert err <= 1e-10 * ref + 1e-14 * ball(r), (lo, hi, got, ref)
        if ref > 1e-3:
            worst = max(worst, err / ref)
    assert worst < 1e-10


# --------------------------------------------------------------------------------------------
# Lattice packings: volume conservation
# --------------------------------------------------------------------------------------------
def _cubic_lattice(r, lo, hi):
    """Simple cubic lattice of touching spheres (spacing 2r, a site at the origin) covering the box."""
    a = 2.0 * r
    axes = [np.arange(np.floor(low / a) - 1, np.ceil(high / a) + 2) * a for low, high in zip(lo, hi)]
    grid = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([g.ravel() for g in grid])


def test_cubic_lattice_aligned_box_is_pi_over_6():
    r = 12.5  # um-like numbers
    lo = np.zeros(3)
    hi = np.array([20, 16, 6]) * 2 * r  # faces through lattice sites: every face cuts spheres in half
    pd = solid_fraction(_cubic_lattice(r, lo, hi), r, lo, hi)
    assert abs(pd - np.pi / 6) < 1e-12


@pytest.mark.parametrize("offset", [(0.31, 0.77, 0.12), (0.5, 0.5, 0.5), (0.999, 0.001, 0.25)])
def test_cubic_lattice_whole_periods_any_offset_is_pi_over_6(offset):
    """A box spanning whole lattice periods cuts spheres at arbitrary places, yet the pieces of
    each periodic image add up to one ball per cell: PD = pi/6 to rounding."""
    r = 1.0
    lo = np.array(offset) * 2 * r + np.array([-3.0, 1.0, 0.0])
    hi = lo + np.array([7, 5, 3]) * 2 * r
    pd = solid_fraction(_cubic_lattice(r, lo, hi), r, lo, hi)
    assert abs(pd - np.pi / 6) < 1e-12


def test_cubic_lattice_large_box_arbitrary_size():
    r = 0.5
    lo = np.array([0.31, 0.77, 0.12])
    hi = lo + 60.37  # 60.37 periods along each axis: partial cells at the faces
    pd = solid_fraction(_cubic_lattice(r, lo, hi), r, lo, hi)
    assert abs(pd - np.pi / 6) < 1e-3


# --------------------------------------------------------------------------------------------
# Additivity, symmetry, solid_fraction
# --------------------------------------------------------------------------------------------
def test_volume_additivity_under_box_splitting():
    rng = np.random.default_rng(12345)
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([4.0, 3.0, 2.0])
    n = 3000
    centres = rng.uniform(lo - 1.0, hi + 1.0, size=(n, 3))
    radii = rng.uniform(0.05, 1.2, size=n)
    centres[:50, 0] = 1.7  # some centres exactly on the split plane x = 1.7
    whole = sphere_box_volume(centres, radii, lo, hi)
    assert np.count_nonzero(whole) > n // 2
    for axis in range(3):
        for cut in (rng.uniform(lo[axis], hi[axis]), 1.7 if axis == 0 else 0.5 * (lo[axis] + hi[axis])):
            hi_a, lo_b = hi.copy(), lo.copy()
            hi_a[axis] = lo_b[axis] = cut
            parts = sphere_box_volume(centres, radii, lo, hi_a) + sphere_box_volume(centres, radii, lo_b, hi)
            err = np.abs(parts - whole)
            assert np.all(err <= 1e-10 * whole + 1e-15 * ball(radii)), err.max()
            mask = whole > 1e-6 * ball(radii)
            assert np.max(err[mask] / whole[mask]) <= 1e-10
            assert abs(parts.sum() - whole.sum()) <= 1e-12 * whole.sum()


def test_symmetry_under_axis_permutation_and_reflection():
    rng = np.random.default_rng(99)
    centres = rng.uniform(-1, 1, size=(500, 3))
    radii = rng.uniform(0.1, 1.0, size=500)
    lo, hi = np.array([-0.6, -0.3, -0.8]), np.array([0.5, 0.9, 0.2])
    v = sphere_box_volume(centres, radii, lo, hi)
    perm = [2, 0, 1]
    v_perm = sphere_box_volume(centres[:, perm], radii, lo[perm], hi[perm])
    v_refl = sphere_box_volume(-centres, radii, -hi, -lo)
    scale = BALL * radii ** 3
    assert np.max(np.abs(v_perm - v) / scale) < 1e-14
    assert np.max(np.abs(v_refl - v) / scale) < 1e-14


def test_solid_fraction_is_sum_over_box_volume():
    rng = np.random.default_rng(3)
    centres = rng.uniform(-0.5, 2.5, size=(200, 3))
    lo, hi = (0.0, 0.0, 0.0), (2.0, 2.0, 1.0)
    vols = sphere_box_volume(centres, 0.2, lo, hi)
    assert solid_fraction(centres, 0.2, lo, hi) == pytest.approx(vols.sum() / 4.0, rel=1e-15)
    # a single ball inside a unit box
    assert solid_fraction([[0.5, 0.5, 0.5]], 0.5, (0, 0, 0), (1, 1, 1)) == pytest.approx(np.pi / 6, rel=1e-14)


# --------------------------------------------------------------------------------------------
# Malformed input
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "centres, radii, lo, hi, match",
    [
        ([[0, 0, 0]], 1.0, (0, 0, 0), (1, 1, 0), r"box_min must be < box_max.*axis z"),
        ([[0, 0, 0]], 1.0, (2, 0, 0), (1, 1, 1), r"box_min must be < box_max.*axis x"),
        ([[0, 0, 0]], 1.0, (0, 0, 0), (1, 1), r"box_max must be a length-3"),
        ([[0, 0, 0]], 1.0, (0, 0, 0, 0), (1, 1, 1), r"box_min must be a length-3"),
        ([[0, 0, 0]], 1.0, (0, 0, np.nan), (1, 1, 1), r"box bounds must be finite"),
        ([[0, 0, 0], [1, 1, 1]], [1.0, -0.1], (0, 0, 0), (1, 1, 1), r"non-negative.*radius 1"),
        ([[0, 0, 0], [1, 1, 1]], [1.0, 1.0, 1.0], (0, 0, 0), (1, 1, 1), r"radii must be a scalar or have shape"),
        ([[0, 0], [1, 1]], 1.0, (0, 0, 0), (1, 1, 1), r"centres must have shape \(n, 3\)"),
        ([0, 0, 0], 1.0, (0, 0, 0), (1, 1, 1), r"centres must have shape \(n, 3\)"),
        ([[0, np.inf, 0]], 1.0, (0, 0, 0), (1, 1, 1), r"centres must be finite"),
        ([[0, 0, 0]], np.nan, (0, 0, 0), (1, 1, 1), r"radii must be finite"),
    ],
)
def test_malformed_input_raises(centres, radii, lo, hi, match):
    with pytest.raises(ValueError, match=match):
        sphere_box_volume(centres, radii, lo, hi)
    with pytest.raises(ValueError, match=match):
        solid_fraction(centres, radii, lo, hi)


# --------------------------------------------------------------------------------------------
# Caps and the part of a sphere below a plane (MFR across the blade's plane)
# --------------------------------------------------------------------------------------------
def test_cap_volume_textbook_values():
    r = 1.7
    assert cap_volume(0.0, r) == 0.0
    assert cap_volume(r, r) == pytest.approx(0.5 * ball(r), rel=1e-15)  # hemisphere
    assert cap_volume(2 * r, r) == pytest.approx(ball(r), rel=1e-15)
    # a cap of height h as the slab of the ball between r - h and r (independent formula)
    for h in (0.1, 0.9, 2.5):
        assert cap_volume(h, r) == pytest.approx(slab(r, r - h, r), rel=1e-13)
    # heights beyond [0, 2r] are clipped
    np.testing.assert_allclose(cap_volume([-1.0, 5.0], r), [0.0, ball(r)], rtol=1e-15)


def test_sphere_volume_below_a_plane_against_slabs_and_monte_carlo():
    rng = np.random.default_rng(5)
    centres = np.array([-3.0, -0.5, 0.0, 0.3, 0.99, 2.0])
    radii = np.array([1.0, 1.0, 0.7, 0.8, 1.0, 1.5])
    got = sphere_volume_below(centres, radii, 0.0)
    expected = [ball(1.0), slab(1.0, -1.0, 0.5), 0.5 * ball(0.7), slab(0.8, -0.8, -0.3), slab(1.0, -1.0, -0.99), 0.0]
    np.testing.assert_allclose(got, expected, rtol=1e-13, atol=1e-15)
    # Monte Carlo: points uniform in the ball, share with x below the plane
    n = 400_000
    p = rng.normal(size=(n, 3))
    p *= (rng.uniform(size=n) ** (1 / 3) / np.linalg.norm(p, axis=1))[:, None]
    for c in (-0.6, 0.25):
        share = np.mean(c + p[:, 0] < 0.0)
        se = np.sqrt(share * (1 - share) / n)
        assert abs(sphere_volume_below([c], 1.0, 0.0)[0] / ball(1.0) - share) < 4 * se


def test_sphere_volume_below_refuses_bad_input():
    with pytest.raises(ValueError, match="non-negative"):
        sphere_volume_below([0.0], -1.0, 0.0)
    with pytest.raises(ValueError, match="finite"):
        sphere_volume_below([np.nan], 1.0, 0.0)
