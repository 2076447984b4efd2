"""The SLURM profile against a real scheduler: a smoke study run through profiles/slurm on a
single-node SLURM started on this machine (tests/slurm_localhost.py) gives the same results table
as the same study run locally, and its cases really ran as SLURM jobs.

Needs root (the daemons are started by hand) and Debian's slurm-wlm and munge, which it installs
with apt-get when missing (~20 s); skipped, with the reason, only where that cannot be done.
Each run happens in its own temporary copy of the workflow: results/ of the repository is never
touched. Whatever the outcome, the cluster is stopped (its own pids only) and its directory removed.
"""
from __future__ import annotations

import copy
import csv
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from conftest import ROOT
from slurm_localhost import LocalSlurm, SlurmUnavailable, ensure_packages

pytestmark = pytest.mark.slurm

# The study run both ways: the target and the configuration laid over config.yaml (written to a
# file passed with --configfile: `--config` would keep nested values as strings).
SMOKE_STUDY = {
    "target": "results/tables/lds.csv",
    # LDS seed 44: its first four points hold d 22-49 um (28 M sphere-steps at `smoke`); seed 42's
    # hold d 16-43 um (50 M). The test is about SLURM, not the physics. (The ranges cannot be cut to
    # large spheres here: --configfile merges into config.yaml, whose powders lie below d 35 um.)
    "config": {"preset": "smoke", "sweeps": {"lds": {"seed": 44, "partitions": [4]}}},
}
# What a copy of the workflow holds (the venv's editable spreadmap package stays /work/.../spreadmap).
WORKFLOW = ("Snakefile", "config.yaml", "rules", "scripts", "yade_scripts", "schemas", "profiles", "envs")
# Table columns that measure the machine, not the case: the only ones allowed to differ.
MACHINE_COLUMNS = {"wall_time", "cpu_time", "benchmark_s", "max_rss_mb"}  # what the machine, not the model, decides
RUN_TIMEOUT_S = 300  # per snakemake run; the whole test takes ~2 min


@pytest.fixture(scope="module")
def cluster():
    if os.geteuid() != 0:
        pytest.skip("needs root: munged, slurmctld and slurmd are started by hand as root")
    try:
        installed = ensure_packages()
        slurm = LocalSlurm()
        started = time.monotonic()
        slurm.start()  # stops what it started before raising
    except SlurmUnavailable as reason:
        pytest.skip(f"this machine cannot run a localhost SLURM: {reason}")
    # a SIGTERM to pytest (a CI time limit) unwinds through the finally below instead of leaving
    # the daemons behind
    previous = signal.signal(signal.SIGTERM, interrupted)
    try:
        print(f"\n[slurm] packages installed in {installed:.0f} s; cluster up in {time.monotonic() - started:.1f} s "
              f"(pids {slurm.pids}, {slurm.dir})")
        yield slurm
    finally:
        signal.signal(signal.SIGTERM, previous)
        for line in slurm.stop():
            print(f"[slurm] {line}")


def interrupted(signum, frame):
    raise KeyboardInterrupt(f"signal {signum}")


def workflow_copy(directory: Path) -> Path:
    directory.mkdir(parents=True)
    for name in WORKFLOW:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, directory / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy2(source, directory / name)
    (directory / "study.yaml").write_text(yaml.safe_dump(SMOKE_STUDY["config"]))
    return directory


def snakemake(workdir: Path, *args: str, env: dict) -> tuple[str, float]:
    """Run snakemake on the study in workdir; returns its output and wall time. A run that fails or
    overruns fails the test with the tail of its output; an overrun, or an interrupted test, stops
    the run (its own process group: Ctrl-C, under which snakemake cancels its SLURM jobs, then kill)."""
    cmd = [sys.executable, "-m", "snakemake", SMOKE_STUDY["target"], "--configfile", "study.yaml", *args]
    log_path = workdir / "snakemake.out"
    start = time.monotonic()
    with open(log_path, "w") as log:
        proc = subprocess.Popen(cmd, cwd=workdir, env=env, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            code = proc.wait(timeout=RUN_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            stop_run(proc)
            code = f"stopped after {RUN_TIMEOUT_S} s"
        except BaseException:
            stop_run(proc)
            raise
    elapsed = time.monotonic() - start
    output = log_path.read_text(errors="replace")
    assert code == 0, f"`{' '.join(cmd)}` in {workdir}: exit {code}\n" + "\n".join(output.splitlines()[-40:])
    return output, elapsed


def stop_run(proc: subprocess.Popen) -> None:
    for sig, grace in ((signal.SIGINT, 20), (signal.SIGKILL, 10)):
        try:
            os.killpg(proc.pid, sig)
            proc.wait(timeout=grace)
            return
        except ProcessLookupError:
            proc.wait()
            return
        except subprocess.TimeoutExpired:
            continue


def read_table(workdir: Path) -> list[dict]:
    with open(workdir / SMOKE_STUDY["target"], newline="") as f:
        return list(csv.DictReader(f))


def test_smoke_study_through_slurm_equals_local_run(cluster, tmp_path):
    base_env = {k: v for k, v in os.environ.items() if not k.startswith("SLURM_")}

    local = workflow_copy(tmp_path / "local")
    _, local_s = snakemake(local, env=base_env)  # profiles/default: local, 2 cores
    via_slurm = workflow_copy(tmp_path / "slurm")
    output, slurm_s = snakemake(via_slurm, "--workflow-profile", "profiles/slurm", env=cluster.env(base_env))
    print(f"\n[slurm] local run {local_s:.1f} s, run through SLURM {slurm_s:.1f} s")

    # the same results, cell for cell, but for the columns that time the machine
    expected, got = read_table(local), read_table(via_slurm)
    cases = [row["case_id"] for row in expected]
    assert cases and [row["case_id"] for row in got] == cases
    assert all(row["status"] != "failed" for row in expected), [(r["case_id"], r.get("reason")) for r in expected]
    for column in ("mfr", "pd"):
        assert [row[column] for row in got] == [row[column] for row in expected], column
    differing = sorted({c for e, g in zip(expected, got) for c in e if c not in MACHINE_COLUMNS and e[c] != g.get(c)})
    assert not differing, f"columns differing between the local and the SLURM run: {differing}"

    # every case ran as one SLURM job of this run, and nothing else did (the local rules stayed local)
    run_id = re.search(r"SLURM run ID: (\S+)", output)
    assert run_id, "snakemake did not use the SLURM executor"
    run_id = run_id.group(1)
    submitted = dict(re.findall(r"submitted with SLURM jobid (\d+) \(log: (\S+?)\)\.", output))
    jobs = [line.split("|") for line in cluster.client(
        "squeue", "-h", "-t", "all", "--name", run_id, "-o", "%i|%T|%k").stdout.split()]
    assert sorted(comment for _, _, comment in jobs) == sorted(f"rule_run_case_wildcards_{c}" for c in cases)
    assert all(state == "COMPLETED" for _, state, _ in jobs), jobs
    assert {job_id for job_id, _, _ in jobs} == set(submitted)
    for job_id, _, comment in jobs:
        case = comment.removeprefix("rule_run_case_wildcards_")
        log = via_slurm / ".snakemake" / "slurm_logs" / "rule_run_case" / case / f"{job_id}.log"
        assert Path(submitted[job_id]) == log and log.is_file()
        text = log.read_text(errors="replace")
        assert "rule run_case:" in text and f"wildcards: case={case}" in text
        # with the rule's own resources: one CPU, its memory and its runtime (not the partition's)
        resources = re.search(r"^\s*resources: (.*)$", text, re.M).group(1)
        mem_mb, runtime = (int(re.search(rf"\b{name}=(\d+)", resources).group(1)) for name in ("mem_mb", "runtime"))
        details = cluster.client("scontrol", "-o", "show", "job", job_id).stdout
        assert "NumCPUs=1 " in details and f"MinMemoryNode={mem_mb}M " in details, details
        assert f"TimeLimit={runtime // 60:02d}:{runtime % 60:02d}:00 " in details, details
    assert not (local / ".snakemake" / "slurm_logs").exists()


@pytest.mark.faults
@pytest.mark.yade
@pytest.mark.slow
def test_a_requeued_case_finishes_once(cluster, tmp_path):
    """A case's SLURM job pre-empted and requeued (`scontrol requeue`) while YADE simulates: SLURM
    kills it and runs the same job again; Snakemake waits for it (no second submission), the case
    finishes once (one run to the end, one row) and the sweep's table has each case once."""
    from conftest import FAST_SWEEP, deep_update, make_workflow

    wf = make_workflow(tmp_path, deep_update(copy.deepcopy(FAST_SWEEP), {"sweeps": {"lds": {"seed": 42, "partitions": [2]}}}),
                       ("sweeps", "points"))
    env = cluster.env({k: v for k, v in os.environ.items() if not k.startswith("SLURM_")})
    cmd = [sys.executable, "-m", "snakemake", "results/tables/lds.csv", "--workflow-profile", "profiles/slurm"]
    log_path = wf / "snakemake.out"
    started = time.monotonic()
    requeued = None
    with open(log_path, "w") as log:
        proc = subprocess.Popen(cmd, cwd=wf, env=env, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                start_new_session=True)
        try:
            deadline = time.monotonic() + RUN_TIMEOUT_S
            while requeued is None and proc.poll() is None and time.monotonic() < deadline:
                jobs = {Path(path).parent.name: job_id for job_id, path in
                        re.findall(r"submitted with SLURM jobid (\d+) \(log: (\S+?)\)\.", log_path.read_text(errors="replace"))}
                for case, job_id in jobs.items():
                    case_log = wf / "results" / "cases" / case / "run.log"
                    if case_log.exists() and "start:" in case_log.read_text(errors="replace"):  # YADE simulates
                        cluster.client("scontrol", "requeue", job_id)
                        requeued = (case, job_id)
                        break
                time.sleep(0.1)
            held = False  # seen out of RUNNING since the requeue
            while requeued and proc.poll() is None and time.monotonic() < deadline:
                # SLURM may hold a requeued job before it starts again (Reason=BeginTime): release it
                # at once, as an admin would, so that the test does not wait out the hold
                details = cluster.client("scontrol", "-o", "show", "job", requeued[1], check=False).stdout
                if "JobState=PENDING" in details and "Reason=BeginTime" in details:
                    cluster.client("scontrol", "update", f"JobId={requeued[1]}", "StartTime=now", check=False)
                held = held or "JobState=RUNNING" not in details
                if held and ("JobState=RUNNING" in details or "JobState=COMPLETED" in details):
                    break  # running again
                time.sleep(0.5)
            code = proc.wait(timeout=max(1, deadline - time.monotonic()))
        except BaseException:
            stop_run(proc)
            raise
    output = log_path.read_text(errors="replace")
    print(f"\n[slurm] the run with a requeued job took {time.monotonic() - started:.0f} s")
    assert requeued, "no SLURM job was caught simulating:\n" + output[-3000:]
    assert code == 0, output[-5000:]
    case, job_id = requeued
    details = cluster.client("scontrol", "-o", "show", "job", job_id).stdout
    assert "JobState=COMPLETED" in details and "Restarts=1 " in details, details  # requeued once, then finished

    # one SLURM job per case: Snakemake did not submit the requeued case a second time
    submitted = re.findall(r"submitted with SLURM jobid (\d+) \(log: (\S+?)\)\.", output)
    per_case = {}
    for jid, path in submitted:
        per_case.setdefault(Path(path).parent.name, []).append(jid)
    assert per_case[case] == [job_id] and all(len(ids) == 1 for ids in per_case.values()), per_case
    # the case ran to the end once: one "ok after" line of scripts/run_case.py in its job's log
    job_log = (wf / ".snakemake" / "slurm_logs" / "rule_run_case" / case / f"{job_id}.log").read_text(errors="replace")
    assert len(re.findall(rf"^{case}: ok after", job_log, re.M)) == 1, job_log[-3000:]
    table = read_table_at(wf / "results" / "tables" / "lds.csv")
    assert sorted(row["case_id"] for row in table) == sorted(per_case) and len(table) == 2  # one row each
    assert all(row["status"] == "ok" for row in table), [(row["case_id"], row["reason"]) for row in table]


def read_table_at(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))
