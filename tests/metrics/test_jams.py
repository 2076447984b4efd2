"""Jam events (spreadmap.metrics.jams, issue 66): the rule on wedge records of known runs, and on the
real YADE a jam that is physics (a sphere 1.8x the gap under the rigid blade: the event persists when
the step is halved) against an overlap that is numerics (a step too large: the bed blows up, no jam
event is counted, and half the step is sound)."""
from __future__ import annotations

import copy
import math

import pytest
from conftest import run_scene

from spreadmap.case.identity import case_scene
from spreadmap.metrics import case_metrics, jam_events, jam_measures
from spreadmap.metrics.jams import jam_runs

D = 40e-6


def test_runs_are_consecutive_calls_above_the_bound():
    series = [[10, 1.0e-4, 0.12, D], [11, 1.1e-4, 0.15, D], [12, 1.2e-4, 0.05, D],  # a run of 2, then below
              [13, 1.3e-4, 0.2, D], [15, 1.5e-4, 0.2, D]]                           # 13 and 15: not consecutive
    runs = jam_runs(series, 0.1)
    assert [[r[0] for r in run] for run in runs] == [[10, 11], [13], [15]]


def test_an_event_lasts_its_travel_and_names_its_largest_sphere():
    # a wedge dragged over 1.5 d (50 calls), a short squeeze over 0.1 d, an impact below the bound
    dragged = [[100 + i, i * 1.2e-6, 0.12 + 0.001 * i, 2 * D if i == 20 else D] for i in range(51)]
    squeeze = [[300 + i, 1e-3 + i * 1e-6, 0.3, D] for i in range(5)]
    impact = [[400, 2e-3, 0.04, D]]
    events = jam_events(dragged + squeeze + impact, overlap_min=0.1, min_travel=0.5 * D)
    assert len(events) == 1
    assert events[0]["x_end"] - events[0]["x_start"] == pytest.approx(60e-6)
    assert events[0]["diameter"] == 2 * D and events[0]["peak_overlap"] == pytest.approx(0.17)


def test_measures_per_mm_of_travel():
    raw = {"params": {"diameter": D, "gap": 30e-6},
           "snapshots": {"blade_start": {"blade_rear_x": 0.0}, "window_end": {"blade_rear_x": 2e-3}},
           "wedge_series": [[1 + i, i * 1e-6, 0.2, 1.5 * D] for i in range(40)]}
    m = jam_measures(raw, 0.1, 0.5)
    assert m["jam_events"] == 1 and m["jam_events_per_mm"] == pytest.approx(0.5)
    assert m["jam_d_over_h"] == pytest.approx(1.5 * D / 30e-6)
    assert all(math.isnan(v) for v in jam_measures({**raw, "wedge_series": None}, 0.1, 0.5).values())
    assert jam_measures({**raw, "wedge_series": []}, 0.1, 0.5)["jam_events"] == 0


def _run(config, tmp_path, h_um, dt_factor):
    cfg = copy.deepcopy(config)
    cfg["presets"]["smoke"]["dt_factor"] = dt_factor
    _, params = case_scene({"f": 0.3, "d_um": 40.0, "h_um": h_um, "v_mm_s": 10.0}, "smoke", cfg, 1)
    folder = tmp_path / f"h{h_um}_dt{dt_factor}"
    folder.mkdir()
    result, raw = run_scene(params, folder)
    return result, case_metrics(raw, cfg["regime"], cfg["stability"], cfg["metrics"])


@pytest.mark.yade
def test_a_jam_persists_when_the_step_is_halved(config, tmp_path):
    """Spheres of 40 um at a 22 um gap (1.8x: they cannot pass under the blade): one jam event at
    0.35 and at 0.175 of the critical step (measured: 2.49 events per mm at both; the wedge's peak
    overlap 0.34 and 0.38 R, the blade being driven at its speed whatever the force)."""
    events = []
    for dt_factor in (0.35, 0.175):
        result, m = _run(config, tmp_path, 22.0, dt_factor)
        assert result["outcome"] == "ok"
        assert m["jam_events"] >= 1 and m["jam_d_over_h"] > 1.5, m
        events.append(m["jam_events_per_mm"])
    assert events[1] == pytest.approx(events[0], rel=0.5)


@pytest.mark.yade
def test_a_step_too_large_is_numerics_not_a_jam(config, tmp_path):
    """The same spheres at a 60 um gap: at 0.95 of the critical step the bed blows up (overlaps of
    ~2 R, at spheres the blade presses too) and no jam event is counted; at half that step the case
    is sound, with no jam event and wedges below the jam bound."""
    result, m = _run(config, tmp_path, 60.0, 0.95)
    assert result["outcome"] == "blown" and math.isnan(m["jam_events"]) and m["flagged"]
    result, m = _run(config, tmp_path, 60.0, 0.475)
    assert result["outcome"] == "ok" and m["jam_events"] == 0 and not m["flagged"], m
