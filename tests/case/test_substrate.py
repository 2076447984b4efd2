"""The rough substrate's mean hollow depth (spreadmap.case.substrate) against an independent numerical
integral: Monte Carlo over random points of an explicitly built lattice of spheres laid as the scene
lays them (yade_scripts/spreading_case.py), with random depths, the surface at each point the
highest cap over it among all spheres; and the limits derived by hand."""
import math

import numpy as np
import pytest

from spreadmap.case.substrate import COVERED, effective_gap_um, floor_label, mean_hollow_depth

D = 1.0  # lengths in particle diameters
R = 0.5 * D


def lattice(rng, rows: int = 14, per_row: int = 16):
    """Sphere centres (x, y) of the scene's substrate: rows along x at pitch d, rows sqrt(3) R
    apart, odd rows shifted by d/2, the whole lattice at a random offset."""
    x0, y0 = rng.uniform(0, D), rng.uniform(0, math.sqrt(3) * R)
    return np.array([(x0 + i * D + (0.5 * D if j % 2 else 0.0), y0 + j * math.sqrt(3) * R)
                     for j in range(rows) for i in range(per_row)])


def sampled_depths(jitter: float, hole_depth: float | None, realizations: int = 60, points: int = 3000,
                   seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Per realization (new lattice offset, new random depths): the mean depth below z = 0 of the
    upper surface at random points of the lattice's interior, and the share of points under a cap.
    At a point under no cap the depth is hole_depth (None: the point is left out)."""
    rng = np.random.default_rng(seed)
    means, covered = [], []
    for _ in range(realizations):
        centres = lattice(rng)
        tops = -rng.uniform(0.0, jitter * R, len(centres))  # each sphere lowered by u R, u in [0, jitter]
        xy = rng.uniform([4 * D, 4 * math.sqrt(3) * R], [12 * D, 10 * math.sqrt(3) * R], (points, 2))
        r2 = ((xy[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
        cap = np.where(r2 < R * R, tops[None, :] - R + np.sqrt(np.clip(R * R - r2, 0.0, None)), -np.inf)
        surface = cap.max(axis=1)  # the highest cap over each point, among every sphere
        under = np.isfinite(surface)
        depth = -surface[under] if hole_depth is None else np.where(under, -surface, hole_depth * D)
        means.append(depth.mean())
        covered.append(under.mean())
    return np.array(means), np.array(covered)


@pytest.mark.parametrize("jitter", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("hole_depth", [None, 1.0])
def test_mean_hollow_depth_is_the_monte_carlo_integral(jitter, hole_depth):
    means, covered = sampled_depths(jitter, hole_depth)
    estimate, se = means.mean(), means.std(ddof=1) / math.sqrt(len(means))
    assert se < 0.003  # the check resolves the depth to 0.3 % of d (1 % of the depth)
    assert abs(mean_hollow_depth(jitter, hole_depth) - estimate) < 4 * se, (estimate, se)
    se_cov = covered.std(ddof=1) / math.sqrt(len(covered))
    assert abs(covered.mean() - COVERED) < 4 * se_cov + 1e-4


def test_limits_derived_by_hand():
    # jitter 0: a hexagonal layer of touching spheres with their tops at z = 0; over its disc a
    # hemispherical cap lies on average R/3 = d/6 below its top
    assert mean_hollow_depth(0.0) == pytest.approx(1 / 6, abs=1e-15)
    # every sphere lowered by jitter x R on average half of that: + jitter R / 2 = jitter d / 4
    assert mean_hollow_depth(0.5) == pytest.approx(7 / 24, abs=1e-15)
    assert mean_hollow_depth(1.0) == pytest.approx(5 / 12, abs=1e-15)
    # over the whole plane with the holes (1 - pi / (2 sqrt 3) of it) at the backstop, d below:
    # pi / (2 sqrt 3) / 6 + 1 - pi / (2 sqrt 3) = 1 - 5 pi / (12 sqrt 3)
    assert mean_hollow_depth(0.0, hole_depth=1.0) == pytest.approx(1 - 5 * math.pi / (12 * math.sqrt(3)), abs=1e-15)
    assert COVERED == pytest.approx(0.9068996821, abs=1e-10)
    with pytest.raises(ValueError):
        mean_hollow_depth(1.5)


def test_effective_gap_by_floor():
    assert effective_gap_um(60.0, 30.0, "flat", math.nan) == 60.0
    assert effective_gap_um(60.0, 30.0, "rough", 0.5) == pytest.approx(60.0 + 30.0 * 7 / 24)  # + 8.75 um
    assert effective_gap_um(60.0, 30.0, "rough", 0.0) == pytest.approx(65.0)
    assert math.isnan(effective_gap_um(60.0, 30.0, math.nan, 0.5))  # floor unknown (an older record)
    assert math.isnan(effective_gap_um(60.0, 30.0, "rough", math.nan))


def test_floor_label_from_the_config():
    rough = floor_label({"scene": {"substrate": {"kind": "rough", "jitter": 0.5}}})
    assert rough.startswith("rough floor (previous layer, jitter 0.5 R)") and "effective gap h + 0.29 d" in rough
    assert floor_label({"scene": {"substrate": {"kind": "flat"}}}).startswith("flat floor")
    assert floor_label({"scene": {}}).startswith("flat floor")  # the schema's default
    assert "jitter 0.2 R" in floor_label({"scene": {"substrate": {"kind": "rough", "jitter": 0.2}}})
    with pytest.raises(ValueError):
        floor_label({"scene": {"substrate": {"kind": "bumpy"}}})
