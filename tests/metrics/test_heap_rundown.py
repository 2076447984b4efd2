"""The heap ahead of the blade (spreadmap.metrics.flow.heap_volume, heap_h2) and the run-down flag
it feeds (stability.min_heap_h2), on constructed snapshots with known answers (no YADE)."""
import copy
import json
import math

import numpy as np
import pytest
import yaml
from conftest import ROOT

from spreadmap.config import ConfigError, validate
from spreadmap.metrics import (
    JAM_COLUMNS,
    MIN_HEAP_H2,
    NEW_COLUMNS,
    SIZE_COLUMNS,
    case_metrics,
    heap_h2,
    heap_volume,
    passed_volume,
)
from spreadmap.table import FLOOR_COLUMNS, LAST_COLUMNS, build_table

D = 30e-6  # sphere diameter, m
R = 0.5 * D
BALL = math.pi / 6 * D ** 3
RULES = {"jam_mfr_max": 0.05, "short_feed_coverage_min": 0.5, "short_feed_thickness_min": 0.25}
SETTINGS = {"pd_clearance_d": 1.0, "pd_slices": 4, "counting_noise_c": 0.45, "within_batches": 8,
            "surface_grid_d": 0.01}
BOUNDS = {"max_overlap_ratio": 0.05, "max_escaped": 0, "min_heap_h2": 0.7}
GAP, WIDTH = 2 * D, 4 * D


def cap(height, r):
    """Textbook volume of a spherical cap of the given height: pi h^2 (3 r - h) / 3."""
    return math.pi * height ** 2 * (3 * r - height) / 3


def snap(positions, rear, radii=None):
    positions = np.asarray(positions, float)
    radii = [R] * len(positions) if radii is None else list(radii)
    return {"positions": positions.tolist(), "radii": radii, "blade_rear_x": rear, "removed_behind_volume": 0.0}


# ------------------------------------------------------------------------ the heap's volume
def test_heap_volume_of_spheres_at_known_places():
    """Blade's rear face at x = 10 d. Ahead: three whole spheres, one of them far ahead; one
    centred on the face (half of it ahead); one 0.2 d behind it (a cap of height R - 0.2 d ahead)
    and one 0.3 d ahead (all but a cap of height R - 0.3 d); behind: two whole ones. The heap is
    the sum of those parts, by the textbook cap formula; what is behind plus what is ahead is every
    sphere."""
    rear = 10 * D
    pos = [[11.0, 0.5, 0.5], [12.0, 1.5, 1.5], [40.0, 2.5, 0.5],  # whole, ahead
           [10.0, 3.5, 0.5],                                      # centred on the face: half
           [9.8, 0.5, 1.5], [10.3, 1.5, 0.5],                     # cut off the centre
           [5.0, 0.5, 0.5], [9.5, 2.5, 1.5]]                      # whole, behind (touching the face)
    s = snap(np.array(pos) * D, rear)
    expected = 3 * BALL + 0.5 * BALL + cap(R - 0.2 * D, R) + (BALL - cap(R - 0.3 * D, R))
    assert heap_volume(s) == pytest.approx(expected, rel=1e-12)
    assert heap_volume(s) + passed_volume(s) == pytest.approx(len(pos) * BALL, rel=1e-12)
    assert heap_h2(s, GAP, WIDTH) == pytest.approx(expected / (WIDTH * GAP ** 2), rel=1e-12)


def test_a_sphere_centred_on_the_face_is_half_a_sphere_whatever_its_radius():
    radii = [0.3 * D, 0.5 * D, 0.8 * D]
    s = snap([[10 * D, 0.0, 0.0]] * 3, 10 * D, radii)
    assert heap_volume(s) == pytest.approx(sum(2 / 3 * math.pi * r ** 3 for r in radii), rel=1e-12)


def test_heap_volume_against_monte_carlo():
    """Random spheres of two sizes around the face: the volume ahead of it against points drawn
    uniformly in each ball (within 4 standard errors)."""
    rng = np.random.default_rng(32)
    centres = rng.uniform((7, 0, 0), (13, 4, 3), size=(50, 3)) * D
    radii = rng.choice([0.4 * D, 0.6 * D], size=50)
    rear = 10.13 * D
    got = heap_volume(snap(centres, rear, radii))
    n = 20_000
    u = rng.normal(size=(len(centres), n, 3))
    u *= rng.uniform(size=(len(centres), n, 1)) ** (1 / 3) / np.linalg.norm(u, axis=2, keepdims=True)
    u *= radii[:, None, None]
    share = np.mean(centres[:, None, 0] + u[..., 0] >= rear, axis=1)
    balls = 4 / 3 * math.pi * radii ** 3
    estimate = float(np.sum(balls * share))
    se = math.sqrt(float(np.sum(balls ** 2 * share * (1 - share) / n)))
    assert abs(got - estimate) < 4 * se


def test_heap_h2_of_a_block_of_bulk_powder():
    """A simple cubic block ahead of the blade, L = 6 d long over the bed's width and H = 3 d
    high: a cross-section L H of powder at solid fraction pi/6, i.e. (pi/6) L H / h^2 = 4.71 h^2
    with h = 2 d (the 4.7 h^2 of bulk powder of scene.pile_reserve, at packing 0.52)."""
    block = [(x, y, z) for x in np.arange(10.5, 16, 1.0) for y in np.arange(0.5, 4, 1.0) for z in (0.5, 1.5, 2.5)]
    s = snap(np.array(block) * D, 10 * D)
    assert heap_h2(s, GAP, WIDTH) == pytest.approx(math.pi / 6 * 6 * 3 / 4, rel=1e-12)


# ------------------------------------------------------------------------ through case_metrics
def record(heap_end_spheres=36, heap_start_spheres=72, status="ok"):
    """A blade at 10 d then 20 d (gap 2 d, bed 4 d wide) over a simple cubic monolayer; ahead of
    it at each snapshot a block of whole spheres 4 wide (heap_*_spheres of them, a multiple of 4),
    in a row of columns from the face on at heights 0.5, 1.5, 2.5 d; one sphere centred on the
    face's plane at each snapshot besides (half of it ahead). Rough substrate spheres (recorded
    apart, in `substrate`) lie under the heap."""
    layer = [(x + 0.5, y + 0.5, 0.5) for x in range(20) for y in range(4)]

    def heap(rear_d, n):
        cells = [(rear_d + 0.5 + i // 12, 0.5 + (i % 12) % 4, 0.5 + (i % 12) // 4) for i in range(n)]
        return cells + [(rear_d, 2.0, 3.5)]  # the one on the face's plane, above the block

    start = [p for p in layer if p[0] < 10] + heap(10.0, heap_start_spheres)
    end = layer + heap(20.0, heap_end_spheres)
    params = {"case_id": "heap", "preset": "smoke", "point": {"f": 0.3, "d_um": 30.0, "h_um": 60.0, "v_mm_s": 10.0},
              "seed": 1, "diameter": D, "gap": GAP, "width": WIDTH, "blade_thickness": 2 * D, "time_step": 1e-7,
              "critical_time_step": 4e-7, "density_scale": 1000.0, "n_particles": len(end)}
    raw = {"status": status, "reason": "" if status == "ok" else "yade exited with code -9", "params": params,
           "peak_overlap_ratio": 0.01, "escaped_particles": 0,
           "substrate": {"positions": [[x * D, y * D, -0.5 * D] for x in range(30) for y in range(4)],
                         "radii": [R] * 120}}
    if status == "ok":
        raw["snapshots"] = {"window_start": snap(np.array(start) * D, 10 * D),
                            "window_end": snap(np.array(end) * D, 20 * D)}
    return raw


def h2(n_whole):
    """n whole spheres and one half ahead of the blade, in h^2."""
    return (n_whole + 0.5) * BALL / (WIDTH * GAP ** 2)


def test_case_metrics_reports_the_heap_at_the_windows_start_and_end():
    """The columns count the powder ahead of the blade, not the substrate under it (120 fixed
    spheres, recorded apart) nor the deposit behind it (the 80 spheres passed)."""
    m = case_metrics(record(), RULES, BOUNDS, SETTINGS)
    assert m["heap_start_h2"] == pytest.approx(h2(72), rel=1e-12)  # 2.39 h^2
    assert m["heap_end_h2"] == pytest.approx(h2(36), rel=1e-12)  # 1.21 h^2
    assert not m["flagged"], m["flag_reason"]
    # appended after every older column, the steady flag's batch z (added later) and the sizes'
    # columns (issue 51) after them, then the jam record's (issue 66)
    tail = list(m)[-len(SIZE_COLUMNS) - len(JAM_COLUMNS) - 3:]
    assert tail[:3] == ["heap_start_h2", "heap_end_h2", "flow_trend_z_batch"] == list(NEW_COLUMNS[-3:])
    assert tail[3:3 + len(SIZE_COLUMNS)] == list(SIZE_COLUMNS)
    assert tail[3 + len(SIZE_COLUMNS):] == list(JAM_COLUMNS)


def test_a_heap_below_the_bound_flags_the_case_naming_the_heap_and_the_bound():
    """12 whole spheres and a half ahead at the window's end: 0.41 h^2 < 0.7 h^2: flagged, the
    reason naming both numbers; the flow's trend (no series here) says nothing."""
    m = case_metrics(record(heap_end_spheres=12), RULES, BOUNDS, SETTINGS)
    assert m["heap_end_h2"] == pytest.approx(h2(12), rel=1e-12)
    assert math.isnan(m["flow_trend_z"])
    assert m["flagged"]
    assert m["flag_reason"] == f"the heap ahead of the blade fell to {h2(12):.2f} h^2 (< 0.7 h^2): the pile ran down"
    assert "0.41 h^2 (< 0.7 h^2)" in m["flag_reason"]
    # the bound is the config's: above a lower one, not flagged; null: never
    assert not case_metrics(record(heap_end_spheres=12), RULES, {**BOUNDS, "min_heap_h2": 0.3}, SETTINGS)["flagged"]
    assert not case_metrics(record(heap_end_spheres=0), RULES, {**BOUNDS, "min_heap_h2": None}, SETTINGS)["flagged"]


def test_the_bound_defaults_to_the_schemas_default_and_the_config_sets_it():
    """A stability section without the key is held to MIN_HEAP_H2, the schema's default; the shipped
    config states it; a negative bound is refused naming the key."""
    assert case_metrics(record(heap_end_spheres=12), RULES, {"max_overlap_ratio": 0.05, "max_escaped": 0},
                        SETTINGS)["flagged"]
    shipped = yaml.safe_load((ROOT / "config.yaml").read_text())
    assert shipped["stability"]["min_heap_h2"] == MIN_HEAP_H2
    del shipped["stability"]["min_heap_h2"]
    assert validate(copy.deepcopy(shipped))["stability"]["min_heap_h2"] == MIN_HEAP_H2
    shipped["stability"]["min_heap_h2"] = -1
    with pytest.raises(ConfigError, match=r"'stability\.min_heap_h2': value -1"):
        validate(shipped)


def test_a_failed_case_without_snapshots_gives_nan_and_no_heap_flag():
    m = case_metrics(record(status="crashed"), RULES, BOUNDS, SETTINGS)
    assert math.isnan(m["heap_start_h2"]) and math.isnan(m["heap_end_h2"])
    assert m["flagged"] and m["flag_reason"] == "crashed: yade exited with code -9"


# ------------------------------------------------------------------------ the results table
def test_old_metrics_without_the_heap_load_with_nan_and_the_columns_come_last(tmp_path):
    """A table of a new case's metrics beside one from before the heap was measured (its
    metrics.json, or a row restored from a published table, has no heap): the old row reads NaN,
    the new columns come after every older column, before the floor's."""
    new = case_metrics(record(), RULES, BOUNDS, SETTINGS)
    old = {k: v for k, v in new.items() if not k.startswith("heap_")}
    files = []
    for i, row in enumerate((old, new)):
        files.append(tmp_path / f"m{i}.json")
        files[-1].write_text(json.dumps(row))
    table = build_table(files, [tmp_path / "none.tsv"] * 2, [{"sweep": "t", "index": i} for i in range(2)])
    assert math.isnan(table.loc[0, "heap_end_h2"]) and table.loc[1, "heap_end_h2"] == pytest.approx(h2(36))
    assert LAST_COLUMNS[-3:-1] == ["heap_start_h2", "heap_end_h2"]  # the steady flag's batch z after them
    assert list(table.columns[-len(FLOOR_COLUMNS) - 3:-len(FLOOR_COLUMNS) - 1]) == ["heap_start_h2", "heap_end_h2"]
    only_old = build_table(files[:1], [tmp_path / "none.tsv"], [{"sweep": "t", "index": 0}])
    assert "heap_end_h2" not in only_old.columns and not only_old.loc[0, "flagged"]
