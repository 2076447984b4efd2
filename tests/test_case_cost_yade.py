"""What a case's CPU buys, on the real YADE binary: the scene's per-phase cost record and its
engine timers, and the frozen deposit (scene.freeze_behind_d), which must leave every sphere in
the record and the case's MFR and PD within noise."""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from conftest import case_params, run_many
from spreadmap.metrics import case_metrics

pytestmark = pytest.mark.yade

POINT = {"f": 0.3, "d_um": 45.0, "h_um": 55.0, "v_mm_s": 10.0}  # h/d 1.2: a long smoke window


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
    jobs = []
    for name, freeze in (("plain", None), ("frozen", 2.0)):
        cfg = copy.deepcopy(config)
        cfg["scene"]["freeze_behind_d"] = freeze
        (tmp_path / name).mkdir()
        jobs.append((case_params(cfg, POINT, "smoke"), tmp_path / name))
    (r_plain, raw_plain), (r_frozen, raw_frozen) = run_many(jobs)
    assert r_plain["outcome"] == r_frozen["outcome"] == "ok"
    assert raw_plain["frozen_particles"] == 0 < raw_frozen["frozen_particles"]
    d = raw_frozen["params"]["diameter"]
    end = raw_frozen["snapshots"]["window_end"]
    n_live = raw_frozen["n_particles"] - raw_frozen["rolled_off_particles"]
    assert len(end["positions"]) == n_live  # frozen spheres stay in the record
    at_rest = [p for p, v in zip(end["positions"], end["velocities"]) if not any(v)]
    assert len(at_rest) >= raw_frozen["frozen_particles"]
    assert all(p[0] < end["blade_rear_x"] - 2.0 * d for p in at_rest)
    metrics = {name: case_metrics(raw, config["regime"], config["stability"], config["metrics"])
               for name, raw in (("plain", raw_plain), ("frozen", raw_frozen))}
    for target in ("mfr", "pd"):
        a, b = metrics["plain"], metrics["frozen"]
        sd = math.hypot(a[f"{target}_sd"], b[f"{target}_sd"])
        assert np.isfinite(sd) and abs(a[target] - b[target]) < 3.0 * sd, (target, a[target], b[target], sd)
    assert not metrics["frozen"]["flagged"], metrics["frozen"]["flag_reason"]
