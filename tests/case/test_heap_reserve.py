"""The fed heap's standing reserve (scene.pile_reserve, scene.pile_reserve_d2, scene.pile_reserve_min):
in h^2 at every point, or a fixed number of d^2 clipped between two multiples of h^2 (docs/heap_size).
Pure arithmetic: no YADE."""
from __future__ import annotations

import copy
import math

import pytest
from conftest import case_params

from spreadmap.case.scene import standing_reserve_h2

SCENE = {"pile_reserve": 4.7, "pile_reserve_d2": 40.0, "pile_reserve_min": 1.5, "pile_reserve_d2_from_f": 0.0}


@pytest.mark.parametrize("h_over_d, expected", [
    (1.5, 4.7),                 # 40 d^2 = 17.8 h^2: above the most, so 4.7 h^2 (the thin gaps unchanged)
    (40 ** 0.5 / 4.7 ** 0.5, 4.7),  # h/d 2.92: 40 d^2 is exactly 4.7 h^2
    (3.5, 40 / 3.5 ** 2),       # 3.27 h^2 = 40 d^2
    (5.0, 1.6),                 # 40 / 25
    (5.8, 1.5),                 # 40 d^2 = 1.19 h^2: below the least, so 1.5 h^2
    (7.5, 1.5),
])
def test_the_reserve_is_forty_d2_between_1_5_and_4_7_h2(h_over_d, expected):
    d = 10e-6
    assert standing_reserve_h2(SCENE, d, h_over_d * d) == pytest.approx(expected, rel=1e-12)


def test_without_a_d2_reserve_it_is_pile_reserve_at_every_point():
    scene = {**SCENE, "pile_reserve_d2": None}
    assert [standing_reserve_h2(scene, 10e-6, r * 10e-6) for r in (1.1, 3.5, 7.5)] == [4.7, 4.7, 4.7]
    # a reserve of 0 stays 0 whatever the least is
    assert standing_reserve_h2({**SCENE, "pile_reserve": 0.0}, 10e-6, 70e-6) == 0.0


def test_the_scene_feeds_to_the_reserve_at_the_point(config):
    """The fed heap's target count is the reserve at the point (40 d^2 at h/d 3.5, 4.7 h^2 at h/d 1.5)
    x h^2 plus the gap under the blade, in spheres at the packing guess; at h/d 1.5 the case is
    the one pile_reserve_d2: null gives (same parameters)."""
    with_d2, without = copy.deepcopy(config), copy.deepcopy(config)
    with_d2["scene"].update(fed_heap=True, pile_reserve=4.7, pile_reserve_d2=40.0, pile_reserve_min=1.5)
    without["scene"].update(fed_heap=True, pile_reserve=4.7, pile_reserve_d2=None)
    wide = {"f": 0.3, "d_um": 20.0, "h_um": 70.0, "v_mm_s": 10.0}
    params = case_params(with_d2, wide, "default")
    d, h = 20e-6, 70e-6
    sphere = math.pi * d ** 3 / 6.0
    blade = config["scene"]["blade_thickness_d"] * d
    expected = config["scene"]["packing_guess"] * params["width"] * (40.0 * d * d + blade * h) / sphere
    assert abs(params["feed_count"] - expected) <= 0.5
    assert params["feed_count"] < case_params(without, wide, "default")["feed_count"]
    thin = {"f": 0.3, "d_um": 40.0, "h_um": 60.0, "v_mm_s": 10.0}
    a, b = case_params(with_d2, thin, "default"), case_params(without, thin, "default")
    assert {k: v for k, v in a.items() if k != "case_id"} == {k: v for k, v in b.items() if k != "case_id"}


def test_the_d2_reserve_holds_from_its_friction_on():
    """scene.pile_reserve_d2_from_f 0.30: below it the heap is pile_reserve h^2 (40 d^2 read 35 % low
    at f 0.16), at and above it 40 d^2 between the bounds; without the point's friction it says so."""
    scene = {**SCENE, "pile_reserve_d2_from_f": 0.30}
    d, h = 10e-6, 58e-6  # h/d 5.8: the d^2 rule's 1.5 h^2
    assert standing_reserve_h2(scene, d, h, 0.16) == 4.7
    assert standing_reserve_h2(scene, d, h, 0.2999) == 4.7
    assert standing_reserve_h2(scene, d, h, 0.30) == 1.5
    assert standing_reserve_h2(scene, d, h, 0.45) == 1.5
    assert standing_reserve_h2(scene, d, 35e-6, 0.31) == pytest.approx(40 / 3.5 ** 2, rel=1e-12)
    with pytest.raises(ValueError, match="friction"):
        standing_reserve_h2(scene, d, h)
    # 0 (the schema's default): at every friction, as before the key
    assert standing_reserve_h2({**SCENE, "pile_reserve_d2_from_f": 0.0}, d, h, 0.16) == 1.5


def test_the_scene_keeps_the_shipped_heap_below_the_friction_and_the_d2_heap_above(config):
    """At h/d 5.8: f 0.2 gives the pile_reserve_d2: null case (the same parameters, the same id), f 0.35
    the 1.5 h^2 heap (fewer spheres fed)."""
    ruled, plain = copy.deepcopy(config), copy.deepcopy(config)
    ruled["scene"].update(fed_heap=True, pile_reserve=4.7, pile_reserve_d2=40.0, pile_reserve_min=1.5,
                          pile_reserve_d2_from_f=0.30)
    plain["scene"].update(fed_heap=True, pile_reserve=4.7, pile_reserve_d2=None)
    low = {"f": 0.2, "d_um": 12.0, "h_um": 70.0, "v_mm_s": 10.0}
    assert case_params(ruled, low, "default") == case_params(plain, low, "default")
    high = {**low, "f": 0.35}
    assert case_params(ruled, high, "default")["feed_count"] < 0.5 * case_params(plain, high, "default")["feed_count"]
