"""Jam events of a case: a sphere pinned under the moving blade and dragged (issue 66).

The scene records, at each control call of the move phase whose blade-pressed overlap reaches 0.03
R, the call's number, the blade's rear x, the overlap / R and the diameter of the wedged sphere
(``wedge_series`` of the raw record; yade_scripts/spreading_case.py, ``record_wedge``). A jam event
is a run of consecutive calls whose overlap is at least ``jam_overlap_ratio`` R and whose blade
travel is at least ``jam_min_travel_d`` diameters (a wedge the rigid blade drags, not an impact).
A case reports the number of events, events per mm of the blade's travel in the move phase, and the
largest wedged sphere of an event over the gap (a coarse-tail sphere jams where it exceeds ~h).
Records from before the jam record (no ``wedge_series``) give NaN.
"""
from __future__ import annotations

import math

JAM_COLUMNS = ("jam_events", "jam_events_per_mm", "jam_d_over_h")


def jam_runs(series, overlap_min: float) -> list[list]:
    """The runs of consecutive control calls at or above overlap_min: each a list of the records
    [call, x, overlap, diameter], in call order."""
    runs: list[list] = []
    for record in sorted(series, key=lambda r: r[0]):
        if record[2] < overlap_min:
            continue
        if runs and record[0] == runs[-1][-1][0] + 1:
            runs[-1].append(record)
        else:
            runs.append([record])
    return runs


def jam_events(series, overlap_min: float, min_travel: float) -> list[dict]:
    """The jam events of a wedge record: runs (``jam_runs``) whose blade travel (last x - first x) is at
    least min_travel [m]; each {x_start, x_end, peak_overlap, diameter} (the largest wedged sphere)."""
    events = []
    for run in jam_runs(series, overlap_min):
        if run[-1][1] - run[0][1] >= min_travel:
            events.append({"x_start": run[0][1], "x_end": run[-1][1], "peak_overlap": max(r[2] for r in run),
                           "diameter": max(r[3] for r in run)})
    return events


def jam_measures(raw: dict, overlap_min: float, min_travel_d: float) -> dict:
    """JAM_COLUMNS of a finished case's raw record (NaN without a wedge record or a move phase)."""
    nan = dict.fromkeys(JAM_COLUMNS, math.nan)
    series = raw.get("wedge_series")
    snapshots = raw.get("snapshots", {})
    if series is None or "blade_start" not in snapshots or "window_end" not in snapshots:
        return nan
    p = raw["params"]
    travel = snapshots["window_end"]["blade_rear_x"] - snapshots["blade_start"]["blade_rear_x"]
    if not travel > 0:
        return nan
    events = jam_events(series, overlap_min, min_travel_d * p["diameter"])
    return {"jam_events": len(events), "jam_events_per_mm": len(events) / (travel * 1e3),
            "jam_d_over_h": max((e["diameter"] for e in events), default=math.nan) / p["gap"]}
