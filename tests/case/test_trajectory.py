"""Case pictures (spreadmap.case.pictures) and VTK export (spreadmap.case.vtk_export), on synthetic raw
results: no YADE needed."""
from __future__ import annotations

import copy
import math

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PatchCollection
from vtk_reader import read_vtk, read_vtk_points

from spreadmap.case.pictures import TABLE_COLUMNS, build_case_figure, choose_moments, plot_case_views, sphere_table, view_window
from spreadmap.case.vtk_export import export_case, write_vtk

D = 20e-6  # sphere diameter, m
GAP = 50e-6
WIDTH = 6 * D
BLADE = 2 * D
SPEED = 0.01  # blade speed, m/s


def _snapshot(rng, blade_rear_x, t, n_pile=60, n_deposit=30, stragglers=()):
    """Spheres in a loose pile ahead of the blade, a layer behind it, and optional far stragglers.
    Radii vary around D/2 so every circle can be matched to its own radius."""
    front = blade_rear_x + BLADE
    pile = np.column_stack([front + rng.uniform(0.0, 8 * D, n_pile), rng.uniform(D / 2, WIDTH - D / 2, n_pile),
                            rng.uniform(D / 2, 5 * D, n_pile)])
    layer = np.column_stack([rng.uniform(-BLADE, blade_rear_x, n_deposit),
                             rng.uniform(D / 2, WIDTH - D / 2, n_deposit), rng.uniform(D / 2, GAP, n_deposit)])
    pos = np.vstack([pile, layer] + ([np.array(stragglers, float)] if stragglers else []))
    n = len(pos)
    radii = rng.uniform(0.4 * D, 0.6 * D, n)
    vel = rng.normal(0.0, 0.3 * SPEED, (n, 3))
    vel[:n_pile, 0] += SPEED
    return {"time": t, "iter": int(t * 1e6), "blade_rear_x": blade_rear_x, "positions": pos.tolist(),
            "radii": radii.tolist(), "velocities": vel.tolist(), "removed_behind_volume": 0.0}


def make_raw(moments=("blade_start", "window_start", "window_middle", "window_end"), seed=0, stragglers=()):
    rng = np.random.default_rng(seed)
    rear = {"blade_start": -BLADE, "window_start": 6 * D, "window_middle": 9 * D, "window_end": 12 * D}
    times = {"blade_start": 0.030, "window_start": 0.030 + (6 * D + BLADE) / SPEED,
             "window_middle": 0.030 + (9 * D + BLADE) / SPEED, "window_end": 0.030 + (12 * D + BLADE) / SPEED}
    snapshots = {m: _snapshot(rng, rear[m], times[m], stragglers=stragglers if m == "window_end" else ())
                 for m in moments}
    return {
        "format": "spreadmap-raw-1", "status": "ok", "reason": "", "n_particles": 90 + len(stragglers),
        "params": {"case_id": "test-f0.3000-d20.000-h50.000-v10.0000-s1", "diameter": D, "gap": GAP,
                   "width": WIDTH, "blade_speed": SPEED, "blade_thickness": BLADE, "friction": 0.3,
                   "point": {"f": 0.3, "d_um": 20.0, "h_um": 50.0, "v_mm_s": 10.0}},
        "geometry": {"width": WIDTH, "gap": GAP, "blade_thickness": BLADE, "blade_top": 12 * D,
                     "floor_x": [-BLADE - 20 * D, 200 * D], "pile_length": 8 * D},
        "window": {"x_start": 6 * D, "x_end": 12 * D},
        "snapshots": snapshots,
    }


def _sphere_collections(fig):
    return {c.get_gid(): c for ax in fig.axes for c in ax.collections
            if isinstance(c, PatchCollection) and str(c.get_gid()).startswith("spheres:")}


# ---------------------------------------------------------------------------------------------
# figure
# ---------------------------------------------------------------------------------------------
def test_choose_moments_prefers_blade_start_middle_end_and_falls_back():
    raw = make_raw()
    assert choose_moments(raw["snapshots"]) == ["blade_start", "window_middle", "window_end"]
    part = make_raw(("blade_start", "window_start", "window_end"))
    assert choose_moments(part["snapshots"]) == ["blade_start", "window_start", "window_end"]
    assert choose_moments(make_raw(("window_end", "window_start"))["snapshots"]) == ["window_start", "window_end"]
    assert choose_moments({}) == []


def test_figure_files_and_csv_with_all_snapshots(tmp_path):
    raw = make_raw()
    paths = plot_case_views(raw, tmp_path / "case_speed")
    assert set(paths) == {"png", "pdf", "csv"}
    assert paths["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert paths["pdf"].read_bytes()[:5] == b"%PDF-"
    table = pd.read_csv(paths["csv"])
    assert tuple(table.columns) == TABLE_COLUMNS
    # every sphere of each drawn moment, in um and mm/s
    for m in ("blade_start", "window_middle", "window_end"):
        snap = raw["snapshots"][m]
        rows = table[table["moment"] == m]
        assert len(rows) == len(snap["positions"])
        pos = np.asarray(snap["positions"])
        np.testing.assert_allclose(rows[["x_um", "y_um", "z_um"]].to_numpy(), pos * 1e6, rtol=1e-12)
        np.testing.assert_allclose(rows["r_um"].to_numpy(), np.asarray(snap["radii"]) * 1e6, rtol=1e-12)
        speed = np.linalg.norm(np.asarray(snap["velocities"]), axis=1) * 1e3
        np.testing.assert_allclose(rows["speed_mm_s"].to_numpy(), speed, rtol=1e-12)
    assert set(table["moment"]) == {"blade_start", "window_middle", "window_end"}
    # units sanity: diameters of ~20 um, speeds of the order of the blade's 10 mm/s
    assert 7.0 < table["r_um"].median() < 13.0
    assert 1.0 < table["speed_mm_s"].median() < 30.0


def test_figure_with_some_snapshots_height_colours_and_none(tmp_path):
    raw = make_raw(("window_start", "window_end"))
    paths = plot_case_views(raw, tmp_path / "partial", colour_by="height")
    table = pd.read_csv(paths["csv"])
    assert list(pd.unique(table["moment"])) == ["window_start", "window_end"]
    assert len(table) == sum(len(s["positions"]) for s in raw["snapshots"].values())
    assert paths["png"].stat().st_size > 10_000 and paths["pdf"].stat().st_size > 1_000

    # a poured bed: one snapshot, no blade
    settled = make_raw(("blade_start",))
    settled["snapshots"] = {"settled": {**settled["snapshots"]["blade_start"], "blade_rear_x": None}}
    paths = plot_case_views(settled, tmp_path / "settled")
    assert set(pd.read_csv(paths["csv"])["moment"]) == {"settled"}

    # a failed case without snapshots still gets a (captioned) figure and an empty table
    empty = make_raw(())
    empty.update(status="blown", reason="a sphere reached 9 m/s")
    paths = plot_case_views(empty, tmp_path / "empty")
    assert paths["png"].exists() and paths["pdf"].exists()
    assert tuple(pd.read_csv(paths["csv"]).columns) == TABLE_COLUMNS

    with pytest.raises(ValueError):
        build_case_figure(raw, colour_by="temperature")


def test_spheres_are_circles_to_scale_with_equal_aspect():
    raw = make_raw()
    fig, table = build_case_figure(raw)
    try:
        fig.canvas.draw()
        colls = _sphere_collections(fig)
        assert set(colls) == {f"spheres:{m}:{v}" for m in ("blade_start", "window_middle", "window_end")
                              for v in ("side", "top")}
        for gid, coll in colls.items():
            _, moment, view = gid.split(":")
            rows = table[table["moment"] == moment]
            centres_ref = rows[["x_um", "z_um" if view == "side" else "y_um"]].to_numpy()
            paths = coll.get_paths()
            assert len(paths) == len(rows)
            for path in paths:
                v = path.vertices
                (xa, ya), (xb, yb) = v.min(axis=0), v.max(axis=0)
                centre, rx, ry = np.array([(xa + xb) / 2, (ya + yb) / 2]), (xb - xa) / 2, (yb - ya) / 2
                i = int(np.argmin(np.linalg.norm(centres_ref - centre, axis=1)))
                assert np.allclose(centre, centres_ref[i], atol=1e-6)
                r = rows["r_um"].to_numpy()[i]
                assert rx == pytest.approx(r, rel=1e-6) and ry == pytest.approx(r, rel=1e-6)
        # equal aspect: one um is as long on the page in x as in z (or y), so circles stay circles
        for ax in fig.spreadmap_axes["side"] + fig.spreadmap_axes["top"]:
            bbox = ax.get_window_extent()
            (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
            assert (bbox.width / (x1 - x0)) == pytest.approx(bbox.height / (y1 - y0), rel=0.01)
        # blade: grey rectangle at the recorded position, gap dimensioned and labelled
        ax = fig.spreadmap_axes["side"][-1]
        blade = next(p for p in ax.patches if p.get_gid() == "blade:window_end:side")
        assert blade.get_x() == pytest.approx(12 * D * 1e6)
        assert blade.get_y() == pytest.approx(GAP * 1e6)
        assert blade.get_width() == pytest.approx(BLADE * 1e6)
        assert any(t.get_text() == "h = 50 µm" for t in ax.texts)
        assert any(p.get_gid() == "pd_box:side" for p in ax.patches)
        # title with the case id and parameters with units
        title = " ".join(t.get_text() for t in fig.texts)
        for part in (raw["params"]["case_id"], "f = 0.3", "d = 20 µm", "h = 50 µm", "v = 10 mm/s", "t = "):
            assert part in title
    finally:
        plt.close(fig)


def test_view_focuses_on_pile_blade_and_deposit():
    far = [(150 * D, WIDTH / 2, D / 2), (-25 * D, WIDTH / 2, D / 2)]  # rolled far ahead / behind
    raw = make_raw(stragglers=far)
    win = view_window(raw)
    x0, x1 = win["x"]
    floor = raw["geometry"]["floor_x"]
    assert x0 <= -BLADE * 1e6 and x1 >= (12 * D + BLADE + 8 * D) * 1e6 * 0.95  # blade, deposit, pile
    assert x1 < 60 * D * 1e6 and x0 > -20 * D * 1e6  # not the whole floor, stragglers left out
    assert (x1 - x0) < 0.5 * (floor[1] - floor[0]) * 1e6
    fig, _ = build_case_figure(raw)
    try:
        note = " ".join(t.get_text() for t in fig.texts)
        assert "1 behind" in note and "1 ahead" in note
    finally:
        plt.close(fig)
    # the table keeps the spheres outside the view
    assert len(sphere_table(raw).query("moment == 'window_end'")) == 92


# ---------------------------------------------------------------------------------------------
# VTK
# ---------------------------------------------------------------------------------------------
def test_vtk_round_trip_and_header(tmp_path):
    snap = make_raw()["snapshots"]["window_end"]
    path = write_vtk(snap, tmp_path / "sub" / "end.vtk")
    pos, rad, vel = read_vtk_points(path)
    np.testing.assert_array_equal(pos, np.asarray(snap["positions"]))
    np.testing.assert_array_equal(rad, np.asarray(snap["radii"]))
    np.testing.assert_array_equal(vel, np.asarray(snap["velocities"]))

    n = len(snap["positions"])
    lines = path.read_text().splitlines()
    assert lines[0] == "# vtk DataFile Version 3.0"
    assert 0 < len(lines[1]) < 256
    assert lines[2] == "ASCII"
    assert lines[3] == "DATASET POLYDATA"
    assert lines[4] == f"POINTS {n} double"
    assert f"VERTICES {n} {2 * n}" in lines
    assert f"POINT_DATA {n}" in lines
    for header in ("SCALARS radius double 1", "SCALARS speed double 1", "VECTORS velocity double"):
        assert header in lines
    assert lines.count("LOOKUP_TABLE default") == 2
    # each section holds exactly the declared count of rows
    i = lines.index(f"POINTS {n} double")
    assert all(len(row.split()) == 3 for row in lines[i + 1:i + 1 + n]) and lines[i + 1 + n].startswith("VERTICES")

    data = read_vtk(path)
    assert data["dataset"] == "POLYDATA" and len(data["vertices"]) == n
    assert data["vertices"] == [[k] for k in range(n)]
    np.testing.assert_allclose(data["point_data"]["speed"], np.linalg.norm(np.asarray(snap["velocities"]), axis=1),
                               rtol=1e-15)
    assert [p.name for p in path.parent.iterdir()] == ["end.vtk"]  # no temporary file left


def test_vtk_export_case(tmp_path):
    raw = make_raw()
    paths = export_case(raw, tmp_path / "vtk")
    assert [p.name for p in paths] == ["blade_start.vtk", "window_start.vtk", "window_middle.vtk", "window_end.vtk"]
    for p in paths:
        snap = raw["snapshots"][p.stem]
        pts = read_vtk_points(p)
        np.testing.assert_array_equal(pts.positions, np.asarray(snap["positions"]))
        assert raw["params"]["case_id"] in p.read_text().splitlines()[1]
    assert export_case(make_raw(()), tmp_path / "none") == []

    # overwriting works, an empty snapshot writes a valid empty file
    empty = {"positions": [], "radii": [], "velocities": []}
    p = write_vtk(empty, paths[0])
    assert read_vtk_points(p).positions.shape == (0, 3)

    bad = copy.deepcopy(raw["snapshots"]["window_end"])
    bad["radii"] = bad["radii"][:-1]
    with pytest.raises(ValueError):
        write_vtk(bad, tmp_path / "bad.vtk")
    assert not math.isnan(read_vtk_points(paths[2]).radius.sum())
