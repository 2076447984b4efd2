"""Where a run's wall time went: every job of a Snakemake run (its start and end, from Snakemake's
own log), placed on the cores it ran on, and the core time each kind of job took and the time a
core stood idle (issue 50). Computed here, drawn by ``draw_timeline``.

Snakemake's log (``.snakemake/log/<date>.snakemake.log``) writes ``[<date>]`` then ``rule <name>:``
(or ``localrule``, ``checkpoint``) and the job's ``jobid:`` when a job starts, and ``[<date>]`` then
``Finished jobid: <n> (Rule: <name>)`` when it ends, to the second. A job that started and never
finished (an error, an interrupted run) ends at the log's last time stamp and is marked so.
"""
from __future__ import annotations

import re
from datetime import datetime

import pandas as pd

# What a job is, for the timeline: a DEM case, the loop's own work (its fit and its next batch), the
# analyses after it (surrogate and its validation, maps, decisions, explorer, pictures), or bookkeeping (render, metrics,
# tables: seconds each).
KINDS = {"run_case": "DEM case", "converge_step": "loop step", "converge": "loop step",
         "surrogate": "analysis", "surrogate_validation": "analysis", "maps": "analysis", "decide": "analysis",
         "explorer": "analysis", "predict": "analysis", "case_picture": "analysis", "run_summary": "analysis"}
_STAMP = re.compile(r"^\[(\w{3} \w{3} +\d+ \d\d:\d\d:\d\d \d{4})\]$")
_START = re.compile(r"^(?:local)?(?:rule|checkpoint) (\w+):$")
_JOBID = re.compile(r"^\s+jobid: (\d+)$")
_WILDCARDS = re.compile(r"^\s+wildcards: (.*)$")
_FINISHED = re.compile(r"^Finished jobid: (\d+) \(Rule: (\w+)\)$")


def parse_log(text: str) -> pd.DataFrame:
    """The jobs of one Snakemake log: one row per job that started.

    Parameters
    ----------
    text : str
        The log's text (Snakemake 9's format, above).

    Returns
    -------
    pandas.DataFrame
        ``jobid`` (int), ``rule``, ``kind`` (``KINDS``, else "bookkeeping"), ``wildcards`` (as
        Snakemake wrote them, "" if none), ``start`` and ``end`` (datetime), ``finished`` (bool:
        False for a job whose end the log does not record; its end is then the log's last stamp),
        sorted by start and jobid.
    """
    stamp = None
    last = None
    jobs: dict[int, dict] = {}
    pending = None  # a job whose start line was read, waiting for its jobid
    for line in text.splitlines():
        m = _STAMP.match(line.strip())
        if m:
            stamp = last = datetime.strptime(m.group(1), "%a %b %d %H:%M:%S %Y")
            continue
        m = _START.match(line.strip())
        if m and stamp is not None:
            pending = {"rule": m.group(1), "start": stamp, "wildcards": ""}
            continue
        if pending is not None:
            m = _JOBID.match(line)
            if m:
                jobs[int(m.group(1))] = pending
                pending["jobid"] = int(m.group(1))
                continue
            m = _WILDCARDS.match(line)
            if m and "jobid" in pending:
                pending["wildcards"] = m.group(1)
                continue
        m = _FINISHED.match(line.strip())
        if m and int(m.group(1)) in jobs and stamp is not None:
            jobs[int(m.group(1))]["end"] = stamp
    rows = []
    for jobid, job in jobs.items():
        rows.append({"jobid": jobid, "rule": job["rule"], "kind": KINDS.get(job["rule"], "bookkeeping"),
                     "wildcards": job["wildcards"], "start": job["start"], "end": job.get("end", last),
                     "finished": "end" in job})
    columns = ["jobid", "rule", "kind", "wildcards", "start", "end", "finished"]
    return pd.DataFrame(rows, columns=columns).sort_values(["start", "jobid"], ignore_index=True)


def place_on_cores(jobs: pd.DataFrame) -> pd.DataFrame:
    """Each job on a lane: the lowest lane free at its start (greedy interval partitioning, in start
    order; a job that starts the second another ends takes its lane). DEM cases, loop steps and
    analyses take lanes; bookkeeping jobs (a second or two each) are kept apart on lane -1.

    Parameters
    ----------
    jobs : pandas.DataFrame
        ``parse_log``'s table.

    Returns
    -------
    pandas.DataFrame
        The same rows with ``lane`` (int; -1 for bookkeeping) and ``seconds`` (end - start).
    """
    out = jobs.copy()
    out["seconds"] = (out["end"] - out["start"]).dt.total_seconds()
    lanes: list[datetime] = []  # when each lane frees
    placed = []
    for row in out.itertuples():
        if row.kind == "bookkeeping":
            placed.append(-1)
            continue
        free = [i for i, until in enumerate(lanes) if until <= row.start]
        lane = free[0] if free else len(lanes)
        if lane == len(lanes):
            lanes.append(row.end)
        else:
            lanes[lane] = row.end
        placed.append(lane)
    out["lane"] = placed
    return out


def core_time(placed: pd.DataFrame, cores: int | None) -> dict:
    """The run's wall time and where the cores' time went.

    Parameters
    ----------
    placed : pandas.DataFrame
        ``place_on_cores``' table.
    cores : int or None
        The cores the run had (``--cores``); None: the most jobs that ran at once (a cluster run,
        which has no core count).

    Returns
    -------
    dict
        ``wall_s`` (first start to last end), ``cores``, ``<kind>_s`` (core seconds of each kind but
        bookkeeping, summed over its jobs), ``busy_s`` (their sum), ``idle_s`` (cores x wall - busy,
        at least 0), ``idle_share`` (idle_s / (cores x wall)), ``lanes`` (the most jobs at once) and
        ``unfinished`` (jobs the log saw start and not end).
    """
    if placed.empty:
        return {"wall_s": 0.0, "cores": cores, "busy_s": 0.0, "idle_s": 0.0, "idle_share": float("nan"),
                "lanes": 0, "unfinished": 0}
    wall = (placed["end"].max() - placed["start"].min()).total_seconds()
    working = placed[placed["lane"] >= 0]
    lanes = int(working["lane"].max() + 1) if len(working) else 0
    cores = cores or max(lanes, 1)
    out = {"wall_s": wall, "cores": cores}
    for kind in sorted(set(KINDS.values())):
        out[f"{kind.replace(' ', '_')}_s"] = float(working.loc[working["kind"] == kind, "seconds"].sum())
    out["busy_s"] = float(working["seconds"].sum())
    out["idle_s"] = max(0.0, cores * wall - out["busy_s"])
    out["idle_share"] = out["idle_s"] / (cores * wall) if wall > 0 else float("nan")
    out["lanes"] = lanes
    out["unfinished"] = int((~placed["finished"]).sum())
    return out
