"""MFR, PD and regime on synthetic data with known answers (no YADE)."""
import math

import numpy as np
import pytest

from spreadmap.metrics import PHASES, case_metrics, classify, layer_density, mass_flow_ratio, passed_volume

D = 1.0  # work in units of the diameter
R = 0.5 * D


def cubic_layer(x0, x1, width, layers, spacing=D):
    """Simple cubic spheres with centres at (i + 1/2) spacing, from x0 to x1."""
    xs = np.arange(x0 + 0.5 * spacing, x1, spacing)
    ys = np.arange(0.5 * spacing, width, spacing)
    zs = 0.5 * spacing + spacing * np.arange(layers)
    return np.array([(x, y, z) for x in xs for y in ys for z in zs])


def snapshot(positions, blade_rear_x, removed=0.0):
    return {"positions": positions.tolist(), "radii": [R] * len(positions), "blade_rear_x": blade_rear_x,
            "removed_behind_volume": removed}


def test_mfr_of_a_known_trajectory():
    """A blade leaving behind a simple cubic monolayer (solid fraction pi/6 in a layer of one
    diameter) moves 10 D during the window, with a gap of 2 D: the flow is (pi/6) * (1/2)."""
    width, gap = 4.0, 2.0
    start = snapshot(cubic_layer(0.0, 5.0, width, 1), blade_rear_x=5.0)
    end = snapshot(cubic_layer(0.0, 15.0, width, 1), blade_rear_x=15.0)
    assert mass_flow_ratio(start, end, gap, width) == pytest.approx(math.pi / 6 / 2, rel=1e-12)


def test_mfr_counts_spheres_removed_behind_the_blade():
    width, gap = 4.0, 1.0
    layer = cubic_layer(0.0, 10.0, width, 1)
    start = snapshot(layer[layer[:, 0] < 5.0], blade_rear_x=5.0)
    kept = layer[layer[:, 0] > 2.0]  # the spheres at x < 2 rolled off the back of the floor ...
    removed = (len(layer) - len(kept)) * math.pi / 6  # ... and were removed, their volume kept
    end = snapshot(kept, blade_rear_x=10.0, removed=removed)
    assert passed_volume(end) == pytest.approx(len(layer) * math.pi / 6)
    assert mass_flow_ratio(start, end, gap, width) == pytest.approx(math.pi / 6, rel=1e-12)


def test_mfr_refuses_a_blade_that_did_not_move():
    s = snapshot(cubic_layer(0, 2, 2, 1), 3.0)
    with pytest.raises(ValueError, match="did not advance"):
        mass_flow_ratio(s, s, 1.0, 2.0)


def test_pd_of_a_simple_cubic_bed_is_pi_over_6():
    """Two full cubic layers in a box of height 2 D: pi/6 exactly; a box cutting through the
    upper layer at mid-height also gives pi/6 (exact sphere-box volumes, not centre counts)."""
    pos = cubic_layer(0.0, 12.0, 4.0, 3)
    slices = layer_density(pos, np.full(len(pos), R), 2.0, 10.0, 4.0, 2.0, slices=4)
    np.testing.assert_allclose(slices, math.pi / 6, rtol=1e-12)
    cut = layer_density(pos, np.full(len(pos), R), 2.0, 10.0, 4.0, 1.5, slices=1)
    np.testing.assert_allclose(cut, math.pi / 6, rtol=1e-12)


def test_pd_of_a_half_covered_floor():
    pos = cubic_layer(0.0, 4.0, 4.0, 1)  # spheres only over the first half of an 8 D box
    pd = layer_density(pos, np.full(len(pos), R), 0.0, 8.0, 4.0, 1.0, slices=2)
    np.testing.assert_allclose(pd, [math.pi / 6, 0.0], atol=1e-12)


@pytest.mark.parametrize("mfr,pd,cv,expected", [
    (0.01, 0.01, 0.1, "jamming"), (0.3, 0.1, 0.1, "short_feed"), (0.3, 0.3, 0.6, "short_feed"),
    (0.3, 0.3, 0.1, "normal"),
])
def test_regime_rules(mfr, pd, cv, expected):
    rules = {"jam_mfr_max": 0.05, "short_feed_pd_min": 0.2, "short_feed_cv_max": 0.35}
    assert classify(mfr, pd, cv, rules) == expected


def raw_record(status="ok", overlap=0.001, escaped=0, layers=1):
    d = 30e-6
    scale = d  # positions of the synthetic layer in metres
    end = cubic_layer(0.0, 20.0, 4.0, layers) * scale
    start = end[end[:, 0] < 10.0 * scale]
    params = {"case_id": "x", "preset": "smoke", "point": {"f": 0.3, "d_um": 30.0, "h_um": 60.0, "v_mm_s": 10.0},
              "seed": 1, "diameter": d, "gap": 2 * d, "width": 4 * d, "time_step": 1e-7,
              "critical_time_step": 4e-7, "density_scale": 1000.0, "n_particles": len(end)}
    raw = {"status": status, "reason": "" if status == "ok" else "a sphere reached 9 m/s", "params": params,
           "peak_overlap_ratio": overlap, "escaped_particles": escaped, "final_kinetic_energy": 1.0,
           "kinetic_energy_scale": 10.0}
    if status == "ok":
        raw["snapshots"] = {"window_start": {**snapshot(start, 10.0 * scale), "radii": [0.5 * d] * len(start)},
                            "window_end": {**snapshot(end, 20.0 * scale), "radii": [0.5 * d] * len(end)}}
    return raw


RULES = {"jam_mfr_max": 0.05, "short_feed_pd_min": 0.2, "short_feed_cv_max": 0.35, "pd_slices": 4}
BOUNDS = {"max_overlap_ratio": 0.05, "max_escaped": 0}


def test_case_metrics_of_a_clean_case():
    m = case_metrics(raw_record(layers=2), RULES, BOUNDS)
    assert m["mfr"] == pytest.approx(math.pi / 6) and m["pd"] == pytest.approx(math.pi / 6)
    assert m["regime"] == "normal" and not m["flagged"] and m["time_step_ratio"] == 0.25
    assert m["d_um"] == 30.0 and m["final_ke_per_mgd"] == 0.1


@pytest.mark.parametrize("kind,expected", [
    ({"overlap": 0.2}, "peak overlap"), ({"escaped": 3}, "3 spheres escaped"), ({"status": "blown"}, "blown: a sphere"),
])
def test_a_broken_stability_bound_flags_the_case(kind, expected):
    m = case_metrics(raw_record(**kind), RULES, BOUNDS)
    assert m["flagged"] and expected in m["flag_reason"]


def test_peak_overlap_by_phase_columns():
    raw = raw_record(overlap=0.03)
    assert all(math.isnan(case_metrics(raw, RULES, BOUNDS)[f"peak_overlap_{p}"]) for p in PHASES)  # older records
    raw["peak_overlap_by_phase"] = {"settle": 0.03, "relax": 0.004, "move": 0.01}
    m = case_metrics(raw, RULES, BOUNDS)
    assert [m[f"peak_overlap_{p}"] for p in PHASES] == [0.03, 0.004, 0.01]
