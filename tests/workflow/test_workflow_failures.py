"""The sweep DAG's failures on real Snakemake and YADE (split from test_workflow.py, which keeps the
growth and the run order, so that the two halves run on both workers): a failed case is recorded
with its reason, failed cases are retried on request, a killed run resumes without redoing
finished cases."""
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest
from conftest import FAST_SWEEP, ROOT, SNAKEMAKE, make_workflow, planned_jobs, snakemake
from test_workflow import DROP, lds_only, raw_files

pytestmark = pytest.mark.yade


@pytest.mark.faults
def test_a_failed_case_is_recorded_with_its_reason_and_the_others_finish(tmp_path):
    """A chosen point at a preset with a 2 s outer timeout fails twice (first attempt + one retry),
    is recorded as failed with the reason and its log, and the sweep's cases finish. Issue 35's
    hanging case: the outer timeout ends a run however it hangs (its whole process group killed)."""
    broken = {"presets": {"broken": {**FAST_SWEEP.get("presets", {}), "width_d": 3, "heap_height_d": 4,
                                     "pile_length_min_d": 4, "heap_reserve": 1.2, "transient_d": 1, "window_d": 3,
                                     "dt_factor": 0.35, "density_scale": 1000, "timeout_s": 2}},
              "points": {"named": {"doomed": {"f": 0.3, "d_um": 20.0, "h_um": 60.0, "v_mm_s": 5.0, "preset": "broken"}}}}
    wf = make_workflow(tmp_path, lds_only([3], **broken), DROP)
    run = snakemake(wf, "sweeps")
    assert run.returncode == 0, run.stderr[-3000:]  # the failure is recorded, not fatal
    log = run.stdout + run.stderr
    assert "will be retried" in log  # the first attempt failed and was retried once
    points = pd.read_csv(wf / "results" / "tables" / "points.csv")
    assert points.loc[0, "status"] == "failed" and "timed out after 2 s" in points.loc[0, "reason"]
    assert bool(points.loc[0, "flagged"])
    # the reason names the case's log, which ends with what the launcher did
    case_log = re.search(r"\(log: (\S+)\)$", points.loc[0, "reason"]).group(1)
    assert (wf / case_log).read_text().rstrip().endswith("[launcher] timed out after 2 s wall time (outer timeout); killed")
    lds = pd.read_csv(wf / "results" / "tables" / "lds.csv")
    assert len(lds) == 3 and (lds["status"] == "ok").all()
    summary = json.loads((wf / "results" / "sweeps_summary.json").read_text())
    assert summary["sets"]["points"]["failed"] == 1 and summary["sets"]["lds"]["done"] == 3
    assert "timed out" in summary["sets"]["points"]["problems"][0]["reason"]
    text = (wf / "results" / "sweeps_summary.txt").read_text()
    assert re.search(r"broken-f0\.3000-d20\.000-h60\.000-v5\.0000-s1-[0-9a-f]{8}: failed: timed out", text), text


@pytest.mark.faults
def test_failed_cases_archived_by_retry_failed_run_again_and_finish(tmp_path):
    """The real YADE under a 1 s CPU limit (prlimit, named by SPREADMAP_YADE: the machine kills it,
    as a killed node would) crashes twice per case and both cases are recorded as failed;
    tools/retry_failed.py lists them with their reasons, --archive moves each one's record and log
    into failed-1/, and the same command without the limit runs the same case ids again to ok.
    The archived logs are kept. (The target is the cases' table: `sweeps` would also run the study
    rule, which cannot run on no usable case.)"""
    wf = make_workflow(tmp_path, lds_only([2]), DROP)
    table = "results/tables/lds.csv"
    limited = tmp_path / "yade-1s-cpu"
    limited.write_text(f"#!/bin/sh\nexec prlimit --cpu=1 {shutil.which('yade')} \"$@\"\n")
    limited.chmod(0o755)
    first = subprocess.run([SNAKEMAKE, table], cwd=wf, capture_output=True, text=True, timeout=300,
                           env={**os.environ, "SPREADMAP_YADE": str(limited)})
    assert first.returncode == 0, first.stderr[-3000:]  # recorded, not fatal
    raws = raw_files(wf)
    assert len(raws) == 2 and all(json.loads(p.read_text())["status"] == "failed" for p in raws.values())
    tool = [sys.executable, str(ROOT / "tools" / "retry_failed.py"), str(wf)]
    listed = subprocess.run(tool, capture_output=True, text=True, timeout=60)
    assert listed.returncode == 0 and "2 failed case(s)" in listed.stdout, listed.stdout + listed.stderr
    for case_id in raws:
        assert re.search(rf"^{re.escape(case_id)}: yade exited with code -\d+ \(crashed\)", listed.stdout, re.M), listed.stdout
    assert all(p.exists() for p in raws.values())  # listing moves nothing

    archived = subprocess.run([*tool, "--archive"], capture_output=True, text=True, timeout=60)
    assert archived.returncode == 0, archived.stderr
    logs = {}
    for case_id, raw_path in raws.items():
        archive = raw_path.parent / "failed-1"
        assert not raw_path.exists() and json.loads((archive / "raw.json").read_text())["status"] == "failed"
        assert (raw_path.parent / "case.py").exists() and not (raw_path.parent / "run.log").exists()
        logs[case_id] = (archive / "run.log").read_text()
    assert planned_jobs(snakemake(wf, table, "-n").stdout) == {}  # a missing record alone: not re-made
    command = re.search(r"^  snakemake TARGET (--forcerun .*)$", archived.stdout, re.M).group(1).split()
    assert sorted(command[1:]) == sorted(str(p.relative_to(wf)) for p in raws.values())
    assert planned_jobs(snakemake(wf, table, *command, "-n").stdout)["run_case"] == 2

    again = snakemake(wf, table, *command)
    assert again.returncode == 0, again.stderr[-3000:]
    assert set(raw_files(wf)) == set(raws)  # the same case ids, run again
    assert all(json.loads(p.read_text())["status"] == "ok" for p in raws.values())
    assert (pd.read_csv(wf / table)["status"] == "ok").all()
    for case_id, raw_path in raws.items():  # each failure's log kept beside the new run's
        assert (raw_path.parent / "failed-1" / "run.log").read_text() == logs[case_id] != ""
    assert "no failed cases" in subprocess.run(tool, capture_output=True, text=True, timeout=60).stdout


@pytest.mark.faults
def test_killed_run_resumes_without_redoing_finished_cases(tmp_path):
    cases = 4
    wf = make_workflow(tmp_path, lds_only([cases]), DROP)
    log = open(tmp_path / "killed-run.log", "w")
    proc = subprocess.Popen([SNAKEMAKE, "sweeps", "--cores", "1"], cwd=wf, stdin=subprocess.DEVNULL, stdout=log,
                            stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.time() + 300
        while len(raw_files(wf)) < 2 and time.time() < deadline and proc.poll() is None:
            time.sleep(0.2)
        assert len(raw_files(wf)) >= 2, "no case finished in time:\n" + (tmp_path / "killed-run.log").read_text()[-3000:]
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # kill -9 snakemake and the YADE run it started
        proc.wait()
        log.close()
    finished = {cid: p.read_bytes() for cid, p in raw_files(wf).items()}
    assert 2 <= len(finished) < cases
    dry = planned_jobs(snakemake(wf, "sweeps", "-n").stdout)
    # Snakemake re-plans the unfinished cases, plus any whose YADE run had finished when the kill
    # came but whose job Snakemake had not yet recorded as complete ...
    assert cases - len(finished) <= dry["run_case"] <= cases - len(finished) + 1
    # kill -9 leaves Snakemake's directory lock: the README's resume is --unlock, then run again
    assert snakemake(wf, "--unlock").returncode == 0
    run = snakemake(wf, "sweeps")
    assert run.returncode == 0, (run.stdout + run.stderr)[-6000:]
    after = raw_files(wf)
    assert len(after) == cases
    # ... but no finished case is simulated again: the raw records (which hold each run's wall
    # time) are byte-identical, and the YADE runs of the resume are only the unfinished ones.
    assert all(after[cid].read_bytes() == data for cid, data in finished.items())
    # A re-planned job whose YADE run had finished re-uses that simulation instead of running it.
    done = [line for line in (run.stdout + run.stderr).splitlines() if ": ok after" in line]
    reused = [line for line in done if "re-used the finished simulation" in line]
    assert len(done) == dry["run_case"]
    assert len(done) - len(reused) == cases - len(finished)

