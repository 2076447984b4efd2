"""MFR, PD, the case's noise estimate, the regime and case_metrics on synthetic data with known
answers (no YADE). Layer quality itself: tests/metrics/test_layer.py."""
import math

import numpy as np
import pandas as pd
import pytest

from spreadlab.noise_law.counting import counting_constant, pooled_constant
from spreadmap.metrics import (
    JAM_COLUMNS,
    NEW_COLUMNS,
    PHASES,
    SIZE_COLUMNS,
    batch_means_sd,
    case_metrics,
    classify,
    counting_sd,
    flow_trend,
    layer_density,
    mass_flow_ratio,
    measured_span,
    passed_volume,
)

D = 1.0  # work in units of the diameter
R = 0.5 * D
BALL = math.pi / 6 * D ** 3


def slab(r, z1, z2):
    """Volume of the ball (centre 0, radius r) between z1 and z2 (textbook: pi (r^2 z - z^3/3))."""
    prim = lambda z: math.pi * (r * r * z - z ** 3 / 3.0)  # noqa: E731
    return prim(z2) - prim(z1)


def cubic_layer(x0, x1, width, layers, spacing=D):
    """Simple cubic spheres with centres at (i + 1/2) spacing, from x0 to x1."""
    xs = np.arange(x0 + 0.5 * spacing, x1, spacing)
    ys = np.arange(0.5 * spacing, width, spacing)
    zs = 0.5 * spacing + spacing * np.arange(layers)
    return np.array([(x, y, z) for x in xs for y in ys for z in zs])


def snapshot(positions, blade_rear_x, removed=0.0, radius=R):
    return {"positions": np.asarray(positions).tolist(), "radii": [radius] * len(positions),
            "blade_rear_x": blade_rear_x, "removed_behind_volume": removed}


# ------------------------------------------------------------------------------------------ MFR
def test_mfr_of_a_known_trajectory():
    """A blade leaving behind a simple cubic monolayer (solid fraction pi/6 in a layer of one
    diameter) moves 10 D during the window, with a gap of 2 D: the flow is (pi/6) * (1/2)."""
    width, gap = 4.0, 2.0
    start = snapshot(cubic_layer(0.0, 5.0, width, 1), blade_rear_x=5.0)
    end = snapshot(cubic_layer(0.0, 15.0, width, 1), blade_rear_x=15.0)
    assert mass_flow_ratio(start, end, gap, width) == pytest.approx(math.pi / 6 / 2, rel=1e-12)


def test_passed_volume_counts_the_part_of_each_sphere_behind_the_plane():
    """Spheres cut by the blade's rear plane count by their exact part behind it (textbook slabs),
    not by their centre: a centre on the plane is half a sphere."""
    pos = [[2.0, 0.5, 0.5], [2.3, 0.5, 1.5], [1.9, 1.5, 0.5], [0.0, 1.5, 1.5], [3.0, 2.5, 0.5]]
    got = passed_volume(snapshot(pos, blade_rear_x=2.0, removed=7.0))
    expected = 7.0 + 0.5 * BALL + slab(R, -R, -0.3) + slab(R, -R, 0.1) + BALL + 0.0
    assert got == pytest.approx(expected, rel=1e-13)


def test_passed_volume_against_monte_carlo():
    rng = np.random.default_rng(3)
    centres = rng.uniform((0, 0, 0), (4, 3, 2), size=(60, 3))
    plane = 2.17
    got = passed_volume(snapshot(centres, blade_rear_x=plane))
    # points uniform in each ball; the share with x < plane, times the ball's volume
    n = 20_000
    u = rng.normal(size=(len(centres), n, 3))
    u *= (rng.uniform(size=(len(centres), n, 1)) ** (1 / 3) / np.linalg.norm(u, axis=2, keepdims=True)) * R
    share = np.mean(centres[:, None, 0] + u[..., 0] < plane, axis=1)
    estimate = BALL * share.sum()
    se = BALL * math.sqrt(np.sum(share * (1 - share) / n))
    assert abs(got - estimate) < 4 * se


def test_mfr_with_the_plane_cutting_spheres_differs_from_a_centre_count():
    """Blade rear at x = 5.3 then 15.1 over a long square monolayer (4 spheres a column): behind
    the plane are the whole columns and the part of the cut column (independent slabs); a
    centre count would say 10 columns."""
    width, gap = 4.0, 1.0
    layer = cubic_layer(0.0, 30.0, width, 1)
    start, end = snapshot(layer, 5.3), snapshot(layer, 15.1)
    behind_end = 4 * (15 * BALL + slab(R, -R, -0.4))  # columns 0.5..14.5 whole, 15.5 cut at -0.4
    behind_start = 4 * (5 * BALL + slab(R, -R, -0.2))  # columns 0.5..4.5 whole, 5.5 cut at -0.2
    passed = behind_end - behind_start
    assert mass_flow_ratio(start, end, gap, width) == pytest.approx(passed / (gap * width * 9.8), rel=1e-12)
    by_centre = 4 * 10 * BALL / (gap * width * 9.8)  # centres 5.5 .. 14.5 crossed
    assert abs(mass_flow_ratio(start, end, gap, width) - by_centre) > 1e-3


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


# ------------------------------------------------------------------------------------------- PD
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
    pd_ = layer_density(pos, np.full(len(pos), R), 0.0, 8.0, 4.0, 1.0, slices=2)
    np.testing.assert_allclose(pd_, [math.pi / 6, 0.0], atol=1e-12)


def test_measured_span_ends_a_clearance_behind_the_blade_and_refuses_a_short_box():
    start, end = {"blade_rear_x": 10.0}, {"blade_rear_x": 16.0}
    assert measured_span(start, end, 1.0, 2.0) == (10.0, 15.0)
    assert measured_span(start, end, 4.0, 2.0) == (10.0, 12.0)  # exactly the blade thickness
    with pytest.raises(ValueError, match=r"metrics.pd_clearance_d.*4.5 d.*1.5 d long.*blade thickness 2 d"):
        measured_span(start, end, 4.5, 2.0, diameter=1.0)


# ---------------------------------------------------------------------------------------- noise
def test_counting_sd():
    """36 spheres' worth of a measure of 0.3 (1/120 a sphere): 0.45 / 6 x 0.3; below one sphere
    the SD of one sphere's worth, so a jammed case (nothing passed) keeps a finite weight."""
    assert counting_sd(36.0, 0.3 / 36, 0.45) == pytest.approx(0.45 / 6 * 0.3, rel=1e-15)
    assert counting_sd(0.0, 0.01, 0.45) == counting_sd(0.4, 0.01, 0.45) == pytest.approx(0.0045, rel=1e-15)
    assert math.isnan(counting_sd(math.nan, 0.01, 0.45))


def poisson_series(rng, rate, x0, x1, step, vol=1.0):
    """[time, x, volume] every `step` of blade travel: spheres crossing as a Poisson process of
    `rate` per unit travel, counted whole (by centre) like the scene's series."""
    xs = np.arange(x0, x1 + 1e-9, step)
    crossings = np.sort(rng.uniform(x0 - 5, x1, rng.poisson(rate * (x1 - x0 + 5))))
    counts = np.searchsorted(crossings, xs)
    return np.column_stack([xs, xs, vol * counts])


def test_batch_means_sd_of_a_poisson_flow():
    """Independent crossings at rate k per unit travel: the window's MFR has SD
    sqrt(k L) / (h W L) (volume 1 per sphere); the batch-means variance is unbiased for it."""
    rng = np.random.default_rng(1)
    k, x0, x1, gap, width = 6.0, 10.0, 20.0, 1.0, 2.0
    truth = math.sqrt(k * (x1 - x0)) / (gap * width * (x1 - x0))
    est = []
    for _ in range(400):
        sd, used = batch_means_sd(poisson_series(rng, k, x0, x1, 0.05).tolist(), x0, x1, gap, width, 8)
        assert used == 8
        est.append(sd ** 2)
    # each estimate has chi-square(7) / 7 spread (relative SD 0.53): the mean of 400 within 4 SE
    assert np.mean(est) == pytest.approx(truth ** 2, rel=4 * 0.53 / 20)


def test_batch_means_needs_two_monitor_intervals_per_batch():
    rng = np.random.default_rng(2)
    series = poisson_series(rng, 5.0, 0.0, 10.0, 1.0).tolist()  # 10 intervals in the window
    assert batch_means_sd(series, 0.0, 10.0, 1.0, 1.0, 8)[1] == 5
    assert batch_means_sd(series[:4], 0.0, 10.0, 1.0, 1.0, 8) == (pytest.approx(math.nan, nan_ok=True), 0)
    assert math.isnan(batch_means_sd([], 0.0, 10.0, 1.0, 1.0, 8)[0])


PRESETS = {"a": {"width_d": 5, "window_d": 8}, "b": {"width_d": 8, "window_d": 12}}
POINTS = {"p1": (30.0, 65.0, 0.31), "p2": (50.0, 55.0, 0.20)}


def seed_table(rng, c, seeds=8):
    rows = []
    for preset, geo in PRESETS.items():
        for name, (d, h, m) in POINTS.items():
            n = m * h * geo["width_d"] * d * geo["window_d"] * d / (math.pi * d ** 3 / 6)
            for s in range(seeds):
                rows.append({"preset": preset, "name": name, "f": 0.3, "d_um": d, "h_um": h, "v_mm_s": 10.0,
                             "seed": s, "status": "ok", "flagged": False,
                             "mfr": m * (1 + c / math.sqrt(n) * rng.normal()),
                             "pd": m * (1 + c / math.sqrt(n) * rng.normal())})
    return pd.DataFrame(rows)


def test_counting_constant_recovers_c_and_its_intervals_cover():
    """Seeds drawn with relative SD c / sqrt(N), N from the geometry: c recovered, and the 90 %
    intervals (per cell and pooled) cover the true c about 90 % of the time."""
    rng = np.random.default_rng(4)
    c = 0.45
    cell_hits, pooled_hits, pooled = [], [], []
    for _ in range(150):
        cells = counting_constant(seed_table(rng, c), PRESETS)
        assert len(cells) == 4 and (cells["seeds"] == 8).all()
        cell_hits += list((cells["c_mfr_lo"] <= c) & (c <= cells["c_mfr_hi"]))
        est, lo, hi = pooled_constant(cells, "mfr")
        pooled_hits.append(lo <= c <= hi)
        pooled.append(est)
    assert np.mean(pooled) == pytest.approx(c, rel=0.03)
    # 600 and 150 Bernoulli(0.9): 4 SD = 0.049 and 0.098
    assert abs(np.mean(cell_hits) - 0.9) < 0.05 and abs(np.mean(pooled_hits) - 0.9) < 0.1


def test_counting_constant_leaves_out_failed_and_flagged_cases():
    table = seed_table(np.random.default_rng(5), 0.45)
    table.loc[0, "status"], table.loc[1, "flagged"] = "blown", True
    table.loc[0, "mfr"] = table.loc[1, "mfr"] = 99.0  # would show in the means if counted
    cells = counting_constant(table, PRESETS)
    assert cells["seeds"].tolist() == [6, 8, 8, 8] and cells["mfr_mean"].max() < 1.0


# --------------------------------------------------------------------------------------- regime
RULES = {"jam_mfr_max": 0.05, "short_feed_coverage_min": 0.5, "short_feed_thickness_min": 0.25}


@pytest.mark.parametrize("mfr,coverage,thickness,expected", [
    (0.01, 0.9, 0.6, "jamming"), (0.01, 0.1, 0.1, "jamming"), (0.3, 0.4, 0.6, "short_feed"),
    (0.3, 0.9, 0.2, "short_feed"), (0.3, 0.9, 0.6, "normal"), (0.3, 0.5, 0.25, "normal"), (math.nan, 0.9, 0.6, ""),
])
def test_regime_rules(mfr, coverage, thickness, expected):
    assert classify(mfr, coverage, thickness, RULES) == expected


def test_classify_is_vectorised_and_broadcasts():
    got = classify(np.array([0.01, 0.3, 0.3, 0.3]), np.array([0.9, 0.4, 0.9, 0.9]), 0.6, RULES)
    assert got.dtype == object and got.tolist() == ["jamming", "short_feed", "normal", "normal"]
    grid = classify(np.linspace(0, 0.4, 5)[:, None], np.linspace(0, 1, 3)[None, :], 0.6, RULES)
    assert grid.shape == (5, 3) and grid[0, 2] == "jamming" and grid[4, 0] == "short_feed" and grid[4, 2] == "normal"
    with pytest.raises(KeyError, match="short_feed_coverage_min"):
        classify(0.3, 0.9, 0.6, {"jam_mfr_max": 0.05, "short_feed_pd_min": 0.2})


# ---------------------------------------------------------------------------------- case_metrics
SETTINGS = {"pd_clearance_d": 1.0, "pd_slices": 4, "counting_noise_c": 0.45, "within_batches": 8,
            "surface_grid_d": 0.01}
BOUNDS = {"max_overlap_ratio": 0.05, "max_escaped": 0}
DIAM = 30e-6


def raw_record(status="ok", overlap=0.001, escaped=0, layers=1, row_only=False):
    """A blade at 10 d then 20 d (gap 2 d, bed 4 d wide) over a simple cubic deposit (or a
    single row of spheres along the middle of the bed), in metres; ahead of the blade in both
    snapshots a heap of 36 spheres in a simple cubic block 3 d long and high (36 (pi/6) d^3 /
    (W h^2) = 1.18 h^2, above the run-down bound)."""
    d = DIAM
    layer = cubic_layer(0.0, 20.0, 4.0, layers)
    if row_only:
        layer = layer[np.isclose(layer[:, 1], 1.5) & np.isclose(layer[:, 2], 0.5)]
    heap = cubic_layer(20.0, 23.0, 4.0, 3) * d
    end = np.vstack([layer * d, heap])
    start = np.vstack([layer[layer[:, 0] < 10.0] * d, heap])
    params = {"case_id": "x", "preset": "smoke", "point": {"f": 0.3, "d_um": 30.0, "h_um": 60.0, "v_mm_s": 10.0},
              "seed": 1, "diameter": d, "gap": 2 * d, "width": 4 * d, "blade_thickness": 2 * d, "time_step": 1e-7,
              "critical_time_step": 4e-7, "density_scale": 1000.0, "n_particles": len(end)}
    raw = {"status": status, "reason": "" if status == "ok" else "a sphere reached 9 m/s", "params": params,
           "peak_overlap_ratio": overlap, "escaped_particles": escaped, "final_kinetic_energy": 1.0,
           "kinetic_energy_scale": 10.0}
    if status == "ok":
        raw["snapshots"] = {"window_start": snapshot(start, 10.0 * d, radius=0.5 * d),
                            "window_end": snapshot(end, 20.0 * d, radius=0.5 * d)}
    return raw


def test_case_metrics_of_a_clean_two_layer_case():
    """Two simple cubic layers: MFR = PD = pi/6 (gap 2 d); 10 columns of 8 spheres passed; the
    measured layer (10 d to 19 d) has the hand values of tests/metrics/test_layer.py: coverage pi/4,
    packing 8/11, mean thickness 11 pi d / 24 over a gap of 2 d."""
    m = case_metrics(raw_record(layers=2), RULES, BOUNDS, SETTINGS)
    assert m["mfr"] == pytest.approx(math.pi / 6) and m["pd"] == pytest.approx(math.pi / 6)
    assert m["regime"] == "normal" and not m["flagged"] and m["time_step_ratio"] == 0.25
    assert m["d_um"] == 30.0 and m["final_ke_per_mgd"] == 0.1
    assert m["n_passed"] == pytest.approx(80.0, rel=1e-12)
    assert m["n_pd"] == pytest.approx(72.0, rel=1e-12)  # box 9 d x 4 d x 2 d at pi/6: 72 spheres' worth
    assert m["mfr_sd"] == pytest.approx(0.45 / math.sqrt(80) * math.pi / 6, rel=1e-12)
    assert m["pd_sd"] == pytest.approx(0.45 / math.sqrt(72) * math.pi / 6, rel=1e-12)
    assert m["coverage"] == pytest.approx(math.pi / 4, rel=2e-3)
    assert m["layer_fill"] == pytest.approx(8 / 11, rel=2e-3)
    assert m["thickness_ratio"] == pytest.approx(11 * math.pi / 24 / 2, rel=2e-3)
    assert math.isnan(m["mfr_sd_within"])  # no behind_series in this record
    cols = NEW_COLUMNS + SIZE_COLUMNS + JAM_COLUMNS
    assert list(m)[-len(cols):] == list(cols)  # the new columns come last
    assert math.isnan(m["jam_events"])  # no wedge record in this record (a record from before it)


def test_pd_box_ends_a_clearance_behind_the_blade():
    """A dense blob still in the gap region just behind the blade (within the clearance) does not
    enter PD or the layer measures."""
    raw = raw_record(layers=1)
    end = raw["snapshots"]["window_end"]
    blob = np.array([[19.5, y, 1.5] for y in (0.5, 1.5, 2.5, 3.5)]) * DIAM  # a second layer at 19-20 d
    end["positions"] += blob.tolist()
    end["radii"] += [0.5 * DIAM] * len(blob)
    m = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    assert m["pd"] == pytest.approx(math.pi / 12, rel=1e-12)  # one layer in a box 2 d high
    with_blob = case_metrics(raw, RULES, BOUNDS, {**SETTINGS, "pd_clearance_d": 0.0})
    assert with_blob["pd"] > m["pd"] * 1.05
    with pytest.raises(ValueError, match="metrics.pd_clearance_d"):
        case_metrics(raw, RULES, BOUNDS, {**SETTINGS, "pd_clearance_d": 8.5})


def test_a_jammed_case_keeps_a_finite_noise_estimate():
    """Nothing passed (the deposit of the end snapshot removed): MFR 0, jamming, SDs of one
    sphere's worth (v / (h W travel) = (pi/6) / 80 for MFR, (pi/6) / 72 for the 9 d PD box)."""
    raw = raw_record(layers=1)
    end = raw["snapshots"]["window_end"]
    end["positions"], end["radii"] = raw["snapshots"]["window_start"]["positions"], raw["snapshots"]["window_start"]["radii"]
    m = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    assert m["mfr"] == 0.0 and m["regime"] == "jamming" and m["n_passed"] == 0.0
    assert m["mfr_sd"] == pytest.approx(0.45 * math.pi / 6 / 80, rel=1e-12)
    assert m["pd_sd"] == pytest.approx(0.45 * math.pi / 6 / 72, rel=1e-12)


def test_a_patchy_deposit_is_short_feed_whatever_its_flow():
    """A single row of spheres along a 4 d wide bed: coverage pi/16 < 0.5 -> short feed."""
    m = case_metrics(raw_record(row_only=True), RULES, BOUNDS, SETTINGS)
    assert m["coverage"] == pytest.approx(math.pi / 16, rel=2e-3) and m["regime"] == "short_feed"
    assert m["n_passed"] == pytest.approx(10.0, rel=1e-12)


def test_a_rough_substrate_below_z0_is_not_powder():
    """The substrate is recorded apart (raw["substrate"]); powder spheres sunk into its pockets
    (centres below R) count above z = 0 only: the layer's solid is what lies above the plane."""
    raw = raw_record(layers=1)
    raw["substrate"] = {"positions": [[x * DIAM, 2 * DIAM, -0.5 * DIAM] for x in range(25)], "radii": [0.5 * DIAM] * 25}
    base = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    assert base["mfr"] == pytest.approx(math.pi / 6 / 2) and base["n_passed"] == pytest.approx(40.0)
    for snap in raw["snapshots"].values():  # sink the whole layer by R/2 into the substrate
        snap["positions"] = (np.asarray(snap["positions"]) - [0, 0, 0.25 * DIAM]).tolist()
    sunk = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    assert sunk["mfr"] == base["mfr"]  # MFR is volume across the blade plane, whatever the height
    below = slab(0.5, -0.5, -0.25) / BALL  # share of each sphere below z = 0
    assert sunk["pd"] == pytest.approx(base["pd"] * (1 - below), rel=1e-12)
    assert sunk["thickness_ratio"] == pytest.approx(base["thickness_ratio"] - 0.25 * base["coverage"] / 2, rel=3e-3)


def test_the_table_names_each_cases_floor_and_its_effective_gap(tmp_path):
    """case_metrics carries the floor from the raw record's params (a record from before the floor
    was recorded ran on the scene's default, flat); the table builder adds the effective gap: h on
    the flat floor, h + (1/6 + jitter/4) d on the rough one (spreadmap.case.substrate); the older columns
    keep their places and the floor's come last."""
    import json

    from spreadmap.table import FIRST_COLUMNS, FLOOR_COLUMNS, LAST_COLUMNS, build_table

    old, flat, rough = raw_record(), raw_record(), raw_record()
    flat["params"]["substrate"], flat["params"]["substrate_jitter"] = "flat", 0.5
    rough["params"]["substrate"], rough["params"]["substrate_jitter"] = "rough", 0.5
    rows = [case_metrics(raw, RULES, BOUNDS, SETTINGS) for raw in (old, flat, rough)]
    assert [r["substrate"] for r in rows] == ["flat", "flat", "rough"]
    assert math.isnan(rows[0]["substrate_jitter"]) and math.isnan(rows[1]["substrate_jitter"])  # a jitter on rough only
    assert rows[2]["substrate_jitter"] == 0.5
    files = []
    for i, row in enumerate(rows):
        files.append(tmp_path / f"m{i}.json")
        files[-1].write_text(json.dumps(row))
    table = build_table(files, [tmp_path / "none.tsv"] * 3, [{"sweep": "t", "index": i} for i in range(3)])
    assert list(table.columns[:len(FIRST_COLUMNS)]) == FIRST_COLUMNS
    assert list(table.columns[-len(FLOOR_COLUMNS):]) == FLOOR_COLUMNS
    assert list(table.columns[-len(FLOOR_COLUMNS) - len(LAST_COLUMNS):-len(FLOOR_COLUMNS)]) == LAST_COLUMNS
    assert table["h_eff_um"].tolist() == pytest.approx([60.0, 60.0, 60.0 + 30.0 * 7 / 24])  # d = 30 um: + 8.75 um
    assert table["h_eff_over_d"].tolist() == pytest.approx([2.0, 2.0, 2.0 + 7 / 24])
    # a table of metrics that do not name their floor (published before it was recorded) is as it was
    unnamed = [{k: v for k, v in r.items() if not k.startswith("substrate")} for r in rows]
    for f, row in zip(files, unnamed):
        f.write_text(json.dumps(row))
    table = build_table(files, [tmp_path / "none.tsv"] * 3, [{"sweep": "t", "index": i} for i in range(3)])
    assert not set(FLOOR_COLUMNS) & set(table.columns)


def test_within_case_noise_from_the_behind_series():
    raw = raw_record(layers=1)
    rng = np.random.default_rng(8)
    series = poisson_series(rng, 4.0, 9.0, 20.0, 0.1, vol=BALL * DIAM ** 3)
    series[:, 1] *= DIAM
    raw["behind_series"] = series.tolist()
    m = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    expected = batch_means_sd(series.tolist(), 10 * DIAM, 20 * DIAM, 2 * DIAM, 4 * DIAM, 8)[0]
    assert m["mfr_sd_within"] == expected and 0 < expected < 1


def test_case_metrics_names_a_missing_setting():
    with pytest.raises(KeyError, match="metrics.*surface_grid_d"):
        case_metrics(raw_record(), RULES, BOUNDS, {k: v for k, v in SETTINGS.items() if k != "surface_grid_d"})


@pytest.mark.parametrize("kind,expected", [
    ({"overlap": 0.2}, "peak overlap"), ({"escaped": 3}, "3 spheres escaped"), ({"status": "blown"}, "blown: a sphere"),
])
def test_a_broken_stability_bound_flags_the_case(kind, expected):
    m = case_metrics(raw_record(**kind), RULES, BOUNDS, SETTINGS)
    assert m["flagged"] and expected in m["flag_reason"]
    if kind.get("status") == "blown":
        measured = [k for k in NEW_COLUMNS if not k.startswith("peak_overlap") and k != "wedged"]
        assert all(math.isnan(m[k]) for k in measured) and m["regime"] == ""


@pytest.mark.parametrize("free,wedged,flagged,is_wedged", [
    (0.02, 0.13, False, True),    # a sphere pinned under the blade: reported, kept
    (0.08, 0.0, True, False),     # an impact beyond the bound: flagged
    (0.07, 0.12, True, True),     # both
    (0.02, 0.03, False, False),   # neither
])
def test_the_overlap_flag_reads_the_free_peak_and_reports_a_wedge(free, wedged, flagged, is_wedged):
    raw = raw_record(overlap=max(free, wedged))
    raw["peak_overlap_free"], raw["peak_overlap_wedged"] = free, wedged
    m = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    assert m["flagged"] is flagged and ("peak overlap" in m["flag_reason"]) is flagged
    assert m["wedged"] is is_wedged and m["peak_overlap_free"] == free and m["peak_overlap_wedged"] == wedged
    assert m["peak_overlap_ratio"] == max(free, wedged)


@pytest.mark.parametrize("wedged,bound,flagged", [
    (0.174, None, False),   # the largest published wedge, at the default bound (0.25 R): kept
    (0.26, None, True),     # deeper than any wedge of a sound step: flagged
    (0.26, 0.3, False),     # a looser bound set in the config
    (0.12, 0.1, True),      # a tighter one
    (0.9, "off", False),    # null: never
])
def test_a_wedge_beyond_its_own_bound_is_flagged(wedged, bound, flagged):
    raw = raw_record(overlap=wedged)
    raw["peak_overlap_free"], raw["peak_overlap_wedged"] = 0.02, wedged
    bounds = dict(BOUNDS) if bound is None else {**BOUNDS, "max_wedge_overlap_ratio": None if bound == "off" else bound}
    m = case_metrics(raw, RULES, bounds, SETTINGS)
    assert m["wedged"] and m["flagged"] is flagged
    assert ("at spheres the blade presses" in m["flag_reason"]) is flagged, m["flag_reason"]


@pytest.mark.parametrize("largest_um,jam", [(None, False), (50.0, False), (78.0, True)])
def test_a_deep_wedge_says_whether_the_coarse_tail_jammed(largest_um, jam):
    """A wedge beyond its bound stays flagged; its reason says a jam when the feed's largest sphere
    is wider than the gap (spheres 20-78 um at a 55 um gap), and a step too long otherwise."""
    raw = raw_record(overlap=0.34)
    raw["peak_overlap_free"], raw["peak_overlap_wedged"] = 0.02, 0.34
    raw["params"]["gap"] = 55e-6
    if largest_um is not None:
        raw["params"]["psd_sizes"] = [20e-6, 45e-6, largest_um * 1e-6]
        raw["snapshots"]["blade_start"] = raw["snapshots"]["window_start"]  # the feed the counting reads
    m = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    assert m["flagged"] and "at spheres the blade presses" in m["flag_reason"]
    assert ("a jam of the coarse tail" in m["flag_reason"]) is jam, m["flag_reason"]
    assert ("beyond any wedge of a sound step" in m["flag_reason"]) is not jam
    if jam:
        assert "78 um against a gap of 55 um" in m["flag_reason"]


def test_a_raw_record_from_before_the_split_counts_its_whole_peak_as_free():
    m = case_metrics(raw_record(overlap=0.09), RULES, BOUNDS, SETTINGS)
    assert m["flagged"] and m["peak_overlap_free"] == 0.09 and math.isnan(m["peak_overlap_wedged"]) and not m["wedged"]


def test_peak_overlap_by_phase_columns():
    raw = raw_record(overlap=0.03)
    assert all(math.isnan(case_metrics(raw, RULES, BOUNDS, SETTINGS)[f"peak_overlap_{p}"]) for p in PHASES)
    raw["peak_overlap_by_phase"] = {"settle": 0.03, "relax": 0.004, "move": 0.01}
    m = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    assert [m[f"peak_overlap_{p}"] for p in PHASES] == [0.03, 0.004, 0.01]


def test_regime_probabilities_against_monte_carlo_and_the_plain_rule():
    """Independent normal errors: the probabilities are the shares of classify() over draws."""
    from spreadmap.metrics import regime_probabilities

    rng = np.random.default_rng(6)
    mean = (np.array([0.06, 0.3, 0.3]), np.array([0.9, 0.55, 0.8]), np.array([0.5, 0.5, 0.27]))
    sd = (0.01, 0.05, 0.02)
    got = regime_probabilities(mean[0], sd[0], mean[1], sd[1], mean[2], sd[2], RULES)
    n = 100_000
    draws = [m[:, None] + s * rng.normal(size=(3, n)) for m, s in zip(mean, sd)]
    labels = classify(*draws, RULES)
    for name in ("normal", "jamming", "short_feed"):
        share = (labels == name).mean(axis=1)
        assert np.all(np.abs(got[name] - share) < 4 * np.sqrt(share * (1 - share) / n) + 1e-4), (name, got[name], share)
    np.testing.assert_allclose(sum(got.values()), 1.0, rtol=1e-12)
    plain = regime_probabilities(mean[0], 0.0, mean[1], 0.0, mean[2], 0.0, RULES)
    expected = classify(*mean, RULES)
    for name in ("normal", "jamming", "short_feed"):
        np.testing.assert_array_equal(plain[name], (expected == name).astype(float))


def test_flow_trend_of_a_known_series():
    """Volume passed V(x) = a x + b x^2 (a flow rising linearly with travel): the halves of [x0, x1]
    pass V(xm) - V(x0) and V(x1) - V(xm), worked here by hand; a steady flow gives 0."""
    x = np.linspace(0.0, 30.0, 301)
    a, b, x0, x1 = 2.0, -0.02, 10.0, 20.0
    series = np.column_stack([x, x, a * x + b * x ** 2])
    first = a * 5 + b * (15 ** 2 - 10 ** 2)   # 10 - 2.5 = 7.5
    second = a * 5 + b * (20 ** 2 - 15 ** 2)  # 10 - 3.5 = 6.5
    assert flow_trend(series.tolist(), x0, x1, 1.0, 1.0) == pytest.approx((second - first) / ((first + second) / 2))
    assert flow_trend(series.tolist(), x0, x1, 1.0, 1.0) == pytest.approx(-1.0 / 7.0)
    steady = np.column_stack([x, x, 3.0 * x])
    assert flow_trend(steady.tolist(), x0, x1, 1.0, 1.0) == pytest.approx(0.0, abs=1e-12)
    assert math.isnan(flow_trend(series.tolist(), x0, 40.0, 1.0, 1.0))  # the series ends before the window


def test_flow_trend_z_is_standard_normal_for_a_steady_poisson_flow():
    """Spheres crossing as a Poisson process (c = 1): the trend over its SE 2c / sqrt(N) has mean
    0 and SD 1 over 400 windows (within 4 SE of each), so a steady case is flagged at z < -3 in
    ~0.1 % of runs."""
    rng = np.random.default_rng(3)
    z = []
    for _ in range(400):
        s = poisson_series(rng, 20.0, 9.0, 20.0, 0.05)
        t = flow_trend(s.tolist(), 10.0, 20.0, 1.0, 1.0)
        n = np.interp(20.0, s[:, 1], s[:, 2]) - np.interp(10.0, s[:, 1], s[:, 2])
        z.append(t / (2.0 / math.sqrt(n)))
    assert abs(np.mean(z)) < 4 / math.sqrt(400) and abs(np.std(z) - 1.0) < 4 * 0.71 / math.sqrt(400) * 1.0
    assert np.mean(np.array(z) < -3) < 0.01


def test_a_pile_that_runs_down_flags_the_case():
    """The flow in the window's second half a third of the first's: a trend of -1, ~7 counting-noise
    SEs with the record's 40 spheres passed (flow_trend_z); the series carries no noise at all, so
    in SEs of its within-window noise the fall is infinite (flow_trend_z_batch, the flag's
    statistic): flagged, with the trend."""
    raw = raw_record(layers=1)
    x = np.linspace(9.0, 20.0, 111) * DIAM
    rate = np.where(x < 15 * DIAM, 1.5, 0.5)  # volume per unit travel, in the window's halves
    vol = np.concatenate([[0.0], np.cumsum(rate[:-1] * np.diff(x))]) * 1e-10
    raw["behind_series"] = np.column_stack([x, x, vol]).tolist()
    m = case_metrics(raw, RULES, BOUNDS, SETTINGS)
    assert m["flow_trend"] == pytest.approx(-1.0, rel=0.02)
    assert m["flow_trend_z"] == pytest.approx(-1.0 / (2 * 0.45 / math.sqrt(m["n_passed"])), rel=0.02)
    assert m["flow_trend_z_batch"] == -math.inf
    # the record's heap (36 spheres in a block 3 d long and 3 d high) still holds at the
    # window's end, so the fall is named the flow's own, not a run-down
    assert m["heap_end_h2"] > 0.7
    assert m["flagged"] and m["flag_reason"].endswith(
        f"with {m['heap_end_h2']:.2f} h^2 still ahead of the blade: the flow is unsteady, the pile did not run down")
    # where the heap is below the bound the same fall is a run-down (and the heap's own flag says so)
    thin = dict(BOUNDS, min_heap_h2=m["heap_end_h2"] + 0.01)
    reasons = case_metrics(raw, RULES, thin, SETTINGS)["flag_reason"].split("; ")
    assert reasons[0] == (f"flow fell by {-m['flow_trend']:.0%} over the window "
                          f"({m['flow_trend_z_batch']:.1f} SE of its within-window noise): the pile ran down")
    assert reasons[1].startswith("the heap ahead of the blade fell to")
    steady = dict(BOUNDS, max_flow_trend_z=None)  # null: never flagged for it
    assert not case_metrics(raw, RULES, steady, SETTINGS)["flagged"]
