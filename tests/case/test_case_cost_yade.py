"""What a case's CPU buys, on the real YADE binary: the scene's per-phase cost record and its
engine timers, and the frozen deposit (scene.freeze_behind_d), which must leave every sphere in
the record and the case's MFR and PD within noise."""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from conftest import case_params, run_many, with_preset

from spreadmap.metrics import case_metrics

pytestmark = pytest.mark.yade

POINT = {"f": 0.3, "d_um": 45.0, "h_um": 55.0, "v_mm_s": 10.0}  # h/d 1.2: a long smoke window


def run_pair(config: dict, preset: str, key: str, values: tuple, tmp_path) -> list:
    """The same case (POINT, same seed) with config's scene.<key> set to each of two values, run
    side by side: [(result, raw), (result, raw)]."""
    jobs = []
    for i, value in enumerate(values):
        cfg = copy.deepcopy(config)
        cfg["scene"][key] = value
        (tmp_path / f"run{i}").mkdir()
        jobs.append((case_params(cfg, POINT, preset), tmp_path / f"run{i}"))
    return run_many(jobs)


def assert_same_measurement(raw_plain: dict, raw_other: dict, config: dict) -> None:
    """The other run of the same case reads MFR and PD within 3 recorded SDs (both runs' SDs in
    quadrature) of the plain run, and is not flagged."""
    plain, other = (case_metrics(raw, config["regime"], config["stability"], config["metrics"])
                    for raw in (raw_plain, raw_other))
    for target in ("mfr", "pd"):
        sd = math.hypot(plain[f"{target}_sd"], other[f"{target}_sd"])
        assert np.isfinite(sd) and abs(plain[target] - other[target]) < 3.0 * sd, (target, plain[target], other[target], sd)
    assert not other["flagged"], other["flag_reason"]


def test_phase_cost_splits_the_steps_and_timing_names_every_engine(config, tmp_path):
    params = case_params(config, POINT, "smoke", timing=True)
    (result, raw), = run_many([(params, tmp_path)])
    assert result["outcome"] == "ok", result
    cost = raw["phase_cost"]
    assert list(cost) == ["settle", "relax", "move"]
    # the phases' steps add up to the run's (raw steps count the step that ended it)
    assert sum(c["steps"] for c in cost.values()) == raw["steps"] - 1
    assert all(c["steps"] > 0 and c["spheres"] == params["n_particles"] for c in cost.values())
    for phase, c in cost.items():
        # every sphere has a handful of contacts or near neighbours; contacts are a subset
        assert 0 < c["contacts_at_end"] <= c["interactions_at_end"] < 20 * c["bodies_at_end"], phase
        engines = c["engine_seconds"]
        assert set(engines) == {"reset", "collider", "interactions", "newton", "watchdog", "control", "monitor",
                                "record_overlap"}
        assert engines["interactions"] > engines["collider"] > 0
    # the timers cover the run: their sum is most of YADE's CPU beyond its ~1.5 s start-up, not more
    # than the wall time of the whole process
    timed = sum(sum(c["engine_seconds"].values()) for c in cost.values())
    assert 0.5 * (result["cpu_time"] - 3.0) < timed < result["wall_time"]


def test_frozen_deposit_keeps_every_sphere_and_the_measurement(config, tmp_path):
    """The same case (same seed) with and without freezing the deposit 2 d behind the blade: the
    frozen run freezes spheres, all of them behind that line and at rest in the end snapshot,
    loses none from the record, and reads MFR and PD within 3 recorded SDs of the plain run."""
    (r_plain, raw_plain), (r_frozen, raw_frozen) = run_pair(config, "smoke", "freeze_behind_d", (None, 2.0), tmp_path)
    assert r_plain["outcome"] == r_frozen["outcome"] == "ok"
    assert raw_plain["frozen_particles"] == 0 < raw_frozen["frozen_particles"]
    d = raw_frozen["params"]["diameter"]
    end = raw_frozen["snapshots"]["window_end"]
    n_live = raw_frozen["n_particles"] - raw_frozen["rolled_off_particles"]
    assert len(end["positions"]) == n_live  # frozen spheres stay in the record
    at_rest = [p for p, v in zip(end["positions"], end["velocities"]) if not any(v)]
    assert len(at_rest) >= raw_frozen["frozen_particles"]
    assert all(p[0] < end["blade_rear_x"] - 2.0 * d for p in at_rest)
    assert_same_measurement(raw_plain, raw_frozen, config)


def test_fed_heap_pile_holds_only_what_passes_before_the_window_and_the_reserve(config):
    """Pure arithmetic of the fed pile (no YADE): at a default point the fed pile is the plain pile
    less the window's spheres (pile_margin x target x sphere volume / width, over the heap's share
    of the pile's height), and the heap it is fed to holds the reserve (pile_reserve x h^2) plus
    the gap under the blade, in spheres at the packing guess; the window's length is unchanged."""
    point = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}
    fed_cfg, plain_cfg = copy.deepcopy(config), copy.deepcopy(config)
    fed_cfg["scene"]["fed_heap"], plain_cfg["scene"]["fed_heap"] = True, False
    for cfg in (fed_cfg, plain_cfg):  # both piles hold the whole transient's passing (the shipped fed pile: 3 d of it)
        cfg["presets"]["default"]["pile_transient_d"] = None
    plain = case_params(plain_cfg, point, "default")
    fed = case_params(fed_cfg, point, "default")
    assert plain["feed_count"] is None
    d, h, w = 30e-6, 65e-6, plain["width"]
    sphere = math.pi * d ** 3 / 6.0
    heap = config["presets"]["default"]["heap_height_d"] * d
    packing = config["scene"]["packing_guess"]
    window_part = config["scene"]["pile_margin"] * plain["target_passed"] * sphere / w * heap / (h + heap)
    assert plain["pile_length"] - fed["pile_length"] == pytest.approx(window_part / (packing * heap), rel=1e-9)
    blade = config["scene"]["blade_thickness_d"] * d
    expected = packing * w * (config["scene"]["pile_reserve"] * h * h + blade * h) / sphere
    assert abs(fed["feed_count"] - expected) <= 0.5
    assert fed["window_max_travel"] == plain["window_max_travel"] and fed["target_passed"] == plain["target_passed"]
    assert fed["n_particles"] < 0.75 * plain["n_particles"]


def test_feed_transient_piles_only_the_reserve_and_the_gap_under_the_blade(config):
    """Pure arithmetic (no YADE): with scene.feed_transient the fed pile is shorter by what passes in
    the transient (pile_margin x mfr_expected_max x h x transient, over the heap's share of the pile's
    height), the same at a 3 d and a 5 d transient but for that; the heap it is fed to, the window
    and the target are unchanged; off (the default) the parameters are the shipped ones."""
    point = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}
    d, h = 30e-6, 65e-6
    heap = config["presets"]["default"]["heap_height_d"] * d
    packing = config["scene"]["packing_guess"]
    for transient_d in (3, 5):
        base = copy.deepcopy(config)
        base["presets"]["default"].update(transient_d=transient_d, pile_transient_d=None)
        base["scene"]["fed_heap"] = True
        fed_all = copy.deepcopy(base)
        fed_all["scene"]["feed_transient"] = True
        plain, lever = case_params(base, point, "default"), case_params(fed_all, point, "default")
        transient_part = (config["scene"]["pile_margin"] * config["scene"]["mfr_expected_max"] * h
                          * transient_d * d * heap / (h + heap))
        assert plain["pile_length"] - lever["pile_length"] == pytest.approx(transient_part / (packing * heap), rel=1e-9)
        assert lever["feed_count"] == plain["feed_count"] and lever["target_passed"] == plain["target_passed"]
        assert lever["transient_travel"] == plain["transient_travel"] == pytest.approx(transient_d * d)
        assert lever["n_particles"] < plain["n_particles"]
    off = copy.deepcopy(config)
    off["scene"]["feed_transient"] = False
    assert case_params(off, point, "default") == case_params(config, point, "default")


def test_pile_transient_sizes_the_pile_and_transient_d_the_window(config):
    """Pure arithmetic (no YADE): a window opened 5 d beyond the pile with the pile sized for 3 d
    (presets.default.pile_transient_d, shipped) is the 3 d scene's pile, sphere for sphere, with the
    5 d opening; null (the schema's default) sizes the pile by transient_d itself."""
    point = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}
    def with_transients(transient_d, pile_transient_d):
        cfg = copy.deepcopy(config)
        cfg["scene"]["fed_heap"] = True
        cfg["presets"]["default"].update(transient_d=transient_d, pile_transient_d=pile_transient_d)
        return case_params(cfg, point, "default")

    p3, p5 = with_transients(3, None), with_transients(5, 3)
    for key in ("pile_length", "n_particles", "feed_count", "cloud_height", "target_passed"):
        assert p5[key] == p3[key], key
    assert p5["transient_travel"] == pytest.approx(5 * 30e-6) and p3["transient_travel"] == pytest.approx(3 * 30e-6)
    five = with_transients(5, None)
    assert five["n_particles"] > p5["n_particles"]  # the 5 d pile holds 2 d more
    assert with_transients(5, 5)["pile_length"] == five["pile_length"]
    assert with_transients(3, 3)["pile_length"] == p3["pile_length"]


def test_fed_heap_keeps_the_heap_every_sphere_and_the_measurement(config, tmp_path):
    """The same smoke case (same seed; a 12 d window, so that the fed heap runs below its reserve
    and is fed) from a full pile and from a fed heap: the fed run starts with fewer spheres, adds
    some during the move, keeps every one in the record, holds the heap ahead of the blade near its
    size to the window's end, and reads MFR and PD within 3 recorded SDs of the plain run,
    unflagged (no overlap from the drop)."""
    long_window = with_preset(config, "smoke_long", window_d=12, heap_height_d=5, pile_length_min_d=2)
    (r_plain, raw_plain), (r_fed, raw_fed) = run_pair(long_window, "smoke_long", "fed_heap", (False, True), tmp_path)
    assert r_plain["outcome"] == r_fed["outcome"] == "ok"
    assert raw_plain["fed_particles"] == 0 < raw_fed["fed_particles"]
    assert raw_fed["n_particles"] < raw_plain["n_particles"]
    end = raw_fed["snapshots"]["window_end"]
    assert len(end["positions"]) == raw_fed["n_particles"] + raw_fed["fed_particles"] - raw_fed["rolled_off_particles"]
    ahead = sum(1 for p in end["positions"] if p[0] >= end["blade_rear_x"])
    count, row = raw_fed["params"]["feed_count"], round(raw_fed["params"]["width"] / raw_fed["params"]["diameter"])
    assert count - 3 * row <= ahead <= count + 3 * row, (ahead, count)
    assert_same_measurement(raw_plain, raw_fed, config)
