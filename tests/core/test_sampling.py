"""Sample tables: Halton equals scipy's, prefix property, lower discrepancy than the lattice,
the lattice's corners and spacing."""
import numpy as np
import pytest
from scipy.stats import qmc

from spreadmap.design import NAMES, bounds, to_unit
from spreadmap.sampling import halton, halton_unit, lattice, lattice_unit


def test_halton_equals_scipy_for_the_same_seed():
    ours = halton(64, seed=42)
    ref = qmc.scale(qmc.Halton(d=4, scramble=True, seed=42).random(64), *bounds())
    np.testing.assert_array_equal(ours[list(NAMES)].to_numpy(), ref)
    assert list(ours["index"]) == list(range(64))


def test_lds_n_is_a_prefix_of_lds_2n():
    for n in (4, 17, 100):
        np.testing.assert_array_equal(halton_unit(n, 7), halton_unit(2 * n, 7)[:n])
    assert not np.array_equal(halton_unit(8, 1), halton_unit(8, 2))  # the seed matters


def test_points_inside_the_design_space():
    low, high = bounds()
    pts = halton(500, seed=3)[list(NAMES)].to_numpy()
    assert (pts >= low).all() and (pts <= high).all()
    ranges = {"f": {"min": 0.2, "max": 0.3}}
    assert halton(50, 3, ranges)["f"].between(0.2, 0.3).all()


@pytest.mark.parametrize("k", [3, 4, 5])
def test_halton_discrepancy_lower_than_lattice_at_equal_size(k):
    n = k ** 4
    lat = qmc.discrepancy(lattice_unit(k))
    lds = qmc.discrepancy(halton_unit(n, seed=42))
    print(f"k={k} n={n}: centred L2 discrepancy lattice {lat:.4g}, Halton {lds:.4g}")
    assert lds < lat


def test_lattice_corners_and_spacing():
    k = 4
    table = lattice(k)
    assert len(table) == k ** 4
    unit = to_unit(table[list(NAMES)].to_numpy())
    low, high = bounds()
    for j, name in enumerate(NAMES):
        values = np.unique(table[name])
        assert len(values) == k
        np.testing.assert_allclose(np.diff(values), (high[j] - low[j]) / (k - 1))
        assert values[0] == pytest.approx(low[j]) and values[-1] == pytest.approx(high[j])
    corners = {tuple(c) for c in unit.round(12) if set(c) <= {0.0, 1.0}}
    assert len(corners) == 2 ** 4


def test_lattice_needs_two_points():
    with pytest.raises(ValueError, match="k >= 2"):
        lattice(1)


def test_points_csv_seed_column_takes_reproducible_seeds_only(tmp_path):
    """The CSV's packing seed follows the schema's rule for every other packing seed: an integer
    >= 0 (makeCloud seeds a negative one from the clock; 0 is reproducible in this build)."""
    from spreadmap.sampling import chosen_points

    good = tmp_path / "good.csv"
    good.write_text("name,f,d_um,h_um,v_mm_s,seed\na,0.3,30,65,10,0\nb,0.3,30,65,10,\nc,0.3,30,65,10,7\n")
    assert [p["seed"] for p in chosen_points({"csv": "good.csv"}, tmp_path)] == [0, None, 7]
    for bad in ("-1", "1.5", "x"):
        (tmp_path / "bad.csv").write_text(f"f,d_um,h_um,v_mm_s,seed\n0.3,30,65,10,1\n0.3,30,65,10,{bad}\n")
        with pytest.raises(ValueError,
                           match=rf"row 3, column 'seed': seed = .*{bad}.* is not allowed; a packing seed is an integer >= 0"):
            chosen_points({"csv": "bad.csv"}, tmp_path)
