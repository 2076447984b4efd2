"""The design space as one object (spreadmap.design.Design): built from the config, its bounds,
its maps to and from the unit cube and its axes against numbers written by hand; every reader of
``ranges`` takes it the same as the config's mapping; the one definition of a usable case."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from spreadlab.floors import box_sample
from spreadmap import design
from spreadmap.design import Design, h_over_d
from spreadmap.loop.map_criteria import map_grids
from spreadmap.maps.grids import values
from spreadmap.sampling import halton
from spreadmap.table import usable_cases

RANGES = {"d_um": {"min": 20.0}, "v_mm_s": {"min": 6.0, "max": 12.0}}


def test_from_config_fills_what_the_ranges_leave_out():
    d = Design.from_config({"ranges": RANGES})
    assert d.low == (0.15, 20.0, 55.0, 6.0)
    assert d.high == (0.45, 50.0, 75.0, 12.0)
    assert d.names == ("f", "d_um", "h_um", "v_mm_s")
    assert Design.from_config(None) == Design.from_ranges({}) == Design((0.15, 10.0, 55.0, 5.0), (0.45, 50.0, 75.0, 15.0))
    assert d.ranges["v_mm_s"] == {"min": 6.0, "max": 12.0}
    assert Design.from_ranges(d.ranges) == d  # the config's form round-trips


def test_unit_cube_maps_by_hand():
    d = Design.from_ranges(RANGES)
    corner_low, corner_high = np.zeros(4), np.ones(4)
    np.testing.assert_allclose(d.to_physical(corner_low), [0.15, 20.0, 55.0, 6.0])
    np.testing.assert_allclose(d.to_physical(corner_high), [0.45, 50.0, 75.0, 12.0])
    np.testing.assert_allclose(d.to_physical([0.5, 0.5, 0.5, 0.5]), [0.30, 35.0, 65.0, 9.0])
    np.testing.assert_allclose(d.to_unit([[0.225, 27.5, 60.0, 7.5]]), [[0.25, 0.25, 0.25, 0.25]])
    u = np.random.default_rng(1).random((50, 4))
    np.testing.assert_allclose(d.to_unit(d.to_physical(u)), u, rtol=0, atol=1e-12)


def test_axis_spans_the_range_evenly():
    d = Design.from_ranges(RANGES)
    np.testing.assert_allclose(d.axis("h_um", 5), [55.0, 60.0, 65.0, 70.0, 75.0])
    np.testing.assert_allclose(d.axis("d_um", 4), [20.0, 30.0, 40.0, 50.0])
    assert d.label("v_mm_s") == "blade speed v [mm/s]"


@pytest.mark.parametrize("ranges, name", [({"f": {"min": 0.5, "max": 0.4}}, "f"),
                                          ({"h_um": {"min": 60.0, "max": 60.0}}, "h_um"),
                                          ({"d_um": {"max": float("nan")}}, "d_um")])
def test_an_empty_or_undefined_range_is_refused_by_name(ranges, name):
    with pytest.raises(ValueError, match=name):
        Design.from_ranges(ranges)


def test_h_over_d_by_hand():
    points = pd.DataFrame({"h_um": [65.0, 55.0, 75.0], "d_um": [10.0, 50.0, 30.0]})
    np.testing.assert_allclose(h_over_d(points), [6.5, 1.1, 2.5])
    assert h_over_d({"h_um": 60.0, "d_um": 20.0}) == pytest.approx(3.0)


def test_h_over_d_of_an_array_reads_its_columns_in_the_designs_order():
    """Points as an array (columns f, d_um, h_um, v_mm_s), one or many: the same h/d as by name."""
    X = np.array([[0.2, 10.0, 65.0, 5.0], [0.3, 50.0, 55.0, 15.0], [0.4, 30.0, 75.0, 9.0]])
    np.testing.assert_allclose(h_over_d(X), [6.5, 1.1, 2.5])
    assert h_over_d(X[1]) == pytest.approx(1.1) and h_over_d(X[1]).shape == ()
    assert h_over_d(X.astype(int)).tolist() == [6.5, 1.1, 2.5]  # integers: a float ratio


def test_readers_take_a_design_as_they_take_the_config_mapping():
    """The functions that took the config's ``ranges`` give bit-identical numbers for the Design
    built from it (one object threaded, no second mapping)."""
    d = Design.from_ranges(RANGES)
    assert Design.of(d) is d and Design.of(RANGES) == d and Design.of(None) == Design.from_ranges(None)
    for a, b in zip(design.bounds(RANGES), design.bounds(d), strict=True):
        np.testing.assert_array_equal(a, b)
    grids_a, grids_b = map_grids(None, RANGES), map_grids(None, d)
    for key in ("box", "machine", "powder"):
        np.testing.assert_array_equal(grids_a[key], grids_b[key])
    np.testing.assert_array_equal(box_sample(32, 2, RANGES).to_numpy(), box_sample(32, 2, d).to_numpy())
    np.testing.assert_array_equal(values(None, 9, "f", RANGES), values(None, 9, "f", d))
    pd.testing.assert_frame_equal(halton(16, 3, RANGES), halton(16, 3, d))
    # and the box grid's cell centres lie where they should: (k + 1/2) / box_k of each range
    box = grids_b["box"]
    np.testing.assert_allclose(np.unique(box[:, 1]), [23.0, 29.0, 35.0, 41.0, 47.0])


def test_usable_cases_is_finished_and_not_flagged():
    table = pd.DataFrame({"status": ["ok", "ok", "failed", "ok", "ok"],
                          "flagged": [False, True, False, None, False], "mfr": [0.1, 0.2, None, 0.3, 0.4]},
                         index=[10, 11, 12, 13, 14])
    assert list(usable_cases(table).index) == [10, 13, 14]  # an unset flag is not a flag
    assert list(usable_cases(table.drop(columns="flagged")).index) == [10, 11, 13, 14]
