"""The sweep DAG on real Snakemake and YADE: growth re-uses finished cases, the costliest cases
start first. Its failures (a failed case recorded with its reason, failed cases retried on request,
a killed run resumed) are test_workflow_failures.py, a file of their own so that both workers share
the sweep's runs."""
import copy

import pandas as pd
import pytest
from conftest import FAST_SWEEP, deep_update, make_workflow, planned_jobs, snakemake, write_config

pytestmark = pytest.mark.yade
DROP = ("sweeps", "points")  # the tests give their own


def lds_only(partitions, **extra):
    cfg = copy.deepcopy(FAST_SWEEP)
    cfg["sweeps"] = {"lds": {"seed": 42, "partitions": partitions}}
    return deep_update(cfg, copy.deepcopy(extra))


def raw_files(wf):
    return {p.parent.name: p for p in (wf / "results" / "cases").glob("*/raw.json")}


def test_growing_lds_from_3_to_6_runs_exactly_the_3_new_cases(tmp_path):
    wf = make_workflow(tmp_path, lds_only([3]), DROP)
    assert planned_jobs(snakemake(wf, "sweeps", "-n").stdout)["run_case"] == 3
    run = snakemake(wf, "sweeps")
    assert run.returncode == 0, run.stderr[-3000:]
    before = {cid: (p.read_bytes(), p.stat().st_mtime_ns) for cid, p in raw_files(wf).items()}
    assert len(before) == 3

    write_config(wf, lds_only([3, 6]), DROP)
    dry = snakemake(wf, "sweeps", "-n")
    jobs = planned_jobs(dry.stdout)
    print("dry run after growing 3 -> 6:", jobs)
    assert jobs["run_case"] == 3 and jobs["render_case"] == 3
    run = snakemake(wf, "sweeps")
    assert run.returncode == 0, run.stderr[-3000:]
    after = raw_files(wf)
    assert len(after) == 6
    for cid, (data, mtime) in before.items():  # the first three untouched, byte for byte
        assert after[cid].read_bytes() == data and after[cid].stat().st_mtime_ns == mtime
    table = pd.read_csv(wf / "results" / "tables" / "lds.csv")
    assert list(table["index"]) == list(range(6)) and (table["status"] == "ok").all()
    assert planned_jobs(snakemake(wf, "sweeps", "-n").stdout) == {}  # nothing left to do


def test_the_costliest_cases_start_first(tmp_path):
    """Longest-processing-time order: on one core the YADE runs start in decreasing planned work
    (spheres x planned steps), whatever order the points are listed in (here cheapest first), and
    every render comes before the first run."""
    import re

    from spreadmap import config as spreadmap_config
    from spreadmap.case.identity import case_scene

    points = {f"p{i}": {"f": 0.3, "d_um": d, "h_um": 75, "v_mm_s": 10} for i, d in enumerate((50, 45, 40, 35))}
    cfg = copy.deepcopy(FAST_SWEEP)
    cfg["points"] = {"preset": "smoke", "named": points}
    wf = make_workflow(tmp_path, cfg, DROP)
    config = spreadmap_config.load(wf / "config.yaml")
    work = {}
    for point in points.values():
        cid, scene = case_scene(point, "smoke", config, 1)
        work[cid] = scene["n_particles"] * scene["estimated_steps"]
    assert len(set(work.values())) == 4
    run = snakemake(wf, "points", "--cores", "1")
    assert run.returncode == 0, run.stderr[-3000:]
    log = run.stdout + run.stderr
    jobs = re.findall(r"rule (\w+):\n(?:.*\n)*?\s+wildcards: case=(\S+)", log)
    order = [case for rule, case in jobs if rule == "run_case"]
    assert order == sorted(work, key=work.get, reverse=True), (order, work)
    renders = [i for i, (rule, _) in enumerate(jobs) if rule == "render_case"]
    assert max(renders) < min(i for i, (rule, _) in enumerate(jobs) if rule == "run_case")
