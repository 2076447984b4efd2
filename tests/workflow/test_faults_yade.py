"""Issue 35's faults that need the real YADE binary and Snakemake: a `kill -9` of the whole main
job in the middle of a batch of the adaptive loop, and a `kill -9` of one YADE run. What holds
after each: no finished case runs again, none is lost, and the results are those of an
uninterrupted run of the same configuration, to the last digit.

The loop at its smallest that still has a batch: 4 LDS cases, one step, a batch of 3 (active and
LDS points), a last step at the budget of 7 (smoke cases of large particles, a few seconds each).
The uninterrupted run is made once (module fixture) and both faults are compared with it. A case
that hangs (its outer timeout ends it, it is retried once, recorded as failed with its reason and
log, the sweep goes on) is tests/workflow/test_workflow_failures.py's failed-case test; a requeued SLURM job is in
tests/workflow/test_slurm.py (its cluster fixture)."""
import copy
import csv
import json
import os
import re
import signal
import subprocess
import time
from pathlib import Path

import pytest
from conftest import FAST_SWEEP, SNAKEMAKE, deep_update, make_workflow, planned_jobs, snakemake

pytestmark = [pytest.mark.faults, pytest.mark.yade, pytest.mark.slow]
DROP = ("sweeps", "points")  # the tests give their own
START, BATCH, BUDGET = 4, 3, 7
TINY_LOOP = deep_update(copy.deepcopy(FAST_SWEEP), {
    # the LDS sweep of 2 is the loop's first two cases (one LDS sequence, seed 42): the single-run
    # fault runs only those
    "sweeps": {"lds": {"seed": 42, "partitions": [2]}},
    # a tolerance no smoke run reaches: the loop runs to its budget; the maps and the model at
    # their smallest (the test is about the workflow, not the map)
    "converge": {"start": START, "batch": BATCH, "budget": BUDGET, "k_consecutive": 3,
                 "map_error": {"tolerance": {"mfr": 1e-4, "pd": 1e-4}}},
    "surrogate": {"neurons": [2, 4], "seeds": [0, 1, 2], "cv_folds": 3, "cv_repeats": 1, "gp_restarts": 0,
                  "ensemble_members": 2, "mlp_sizes": [4], "mlp_alphas": [0.1, 1.0]},
    "maps": {"sobol_n": 128, "sobol_draws": 8, "machine": {"n_h": 3, "n_v": 3}},
})
# what the machine decides, not the case: the only columns allowed to differ between two runs
MACHINE_COLUMNS = {"wall_time", "cpu_time", "benchmark_s", "max_rss_mb"}
RUN_LINE = re.compile(r"(\S+-[0-9a-f]{8}): (ok|blown) after [0-9.]+ s ?(.*)$", re.M)  # scripts/run_case.py's line


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    """The loop run once without a fault: the reference both faults are compared with."""
    wf = make_workflow(tmp_path_factory.mktemp("uninterrupted"), TINY_LOOP, DROP)
    started = time.monotonic()
    run = snakemake(wf, "converge")
    assert run.returncode == 0, (run.stdout + run.stderr)[-5000:]
    print(f"\n[faults] the uninterrupted loop took {time.monotonic() - started:.0f} s")
    return wf


def raw_files(wf: Path) -> dict[str, Path]:
    return {p.parent.name: p for p in (wf / "results" / "cases").glob("*/raw.json")}


def yade_runs(wf: Path) -> dict[int, str]:
    """pid -> case id of the YADE processes running a case of this workflow copy."""
    runs = {}
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            args = (proc / "cmdline").read_bytes().decode(errors="replace").split("\0")
        except OSError:
            continue
        if "-x" in args[:-1]:
            script = args[args.index("-x") + 1]
            if script.startswith(str(wf / "results" / "cases")) and script.endswith("case.py"):
                runs[int(proc.name)] = Path(script).parent.name
    return runs


def kill_leftovers(wf: Path) -> list[int]:
    """SIGKILL whatever YADE run of this copy is left (this test's own processes, by pid)."""
    left = list(yade_runs(wf))
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return left


def read_rows(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def assert_same_table(got: list[dict], expected: list[dict]) -> None:
    """Same cases in the same order, MFR and PD as written (to the last digit), every other column
    equal but those that time the machine."""
    assert [r["case_id"] for r in got] == [r["case_id"] for r in expected]
    for column in ("mfr", "pd"):
        assert [r[column] for r in got] == [r[column] for r in expected], column
    differing = sorted({c for g, e in zip(got, expected) for c in e if c not in MACHINE_COLUMNS and e[c] != g.get(c)})
    assert not differing, f"columns differing from the uninterrupted run: {differing}"


def same_record(got: dict, expected: dict) -> bool:
    """Two metrics records equal in every value but those that time the machine (NaN equals NaN)."""
    def text(record):
        return json.dumps({k: v for k, v in record.items() if k not in MACHINE_COLUMNS}, sort_keys=True)
    return text(got) == text(expected)


def simulated_and_reused(output: str) -> tuple[list[str], list[str]]:
    """Case ids whose YADE run finished in this run, and those that re-used a finished simulation."""
    lines = RUN_LINE.findall(output)
    return ([cid for cid, _, why in lines if "re-used" not in why], [cid for cid, _, why in lines if "re-used" in why])


def test_kill_9_of_the_main_job_mid_batch_resumes_to_the_uninterrupted_result(uninterrupted, tmp_path):
    """`kill -9` of the loop's whole process group while a batch runs (a case of the batch done,
    another simulating), `snakemake --unlock`, the same command again: the finished cases and the
    step before the batch are kept byte for byte with their times (not run again), only the rest
    is simulated, no YADE run outlives the kill, and the loop's table equals the uninterrupted
    run's."""
    wf = make_workflow(tmp_path, TINY_LOOP, DROP)
    steps = wf / "results" / "converge"
    log_path = tmp_path / "killed-run.log"
    started = time.monotonic()
    with open(log_path, "w") as log:
        proc = subprocess.Popen([SNAKEMAKE, "converge"], cwd=wf, stdin=subprocess.DEVNULL, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
        try:
            deadline = time.monotonic() + 300
            while proc.poll() is None and time.monotonic() < deadline:
                if (steps / f"step_{START}.json").exists() and len(raw_files(wf)) > START:
                    break  # the step chose its batch, and a case of the batch has finished
                time.sleep(0.05)
            running = yade_runs(wf)
        finally:
            os.killpg(proc.pid, signal.SIGKILL)  # kill -9 of snakemake and every job it started
            proc.wait()
    # YADE's results on disk at the kill: a result that appears later is a YADE run that outlived it
    had_result = {p.parent.name for p in (wf / "results" / "cases").glob("*/simulated.json")}
    try:
        killed_log = log_path.read_text(errors="replace")
        finished = {cid: p.read_bytes() for cid, p in raw_files(wf).items()}
        # YADE's own result beside each raw record: written by its run only
        results = {cid: (p.with_name("simulated.json").read_bytes(), p.with_name("simulated.json").stat().st_mtime_ns)
                   for cid, p in raw_files(wf).items()}
        raw_times = {cid: p.stat().st_mtime_ns for cid, p in raw_files(wf).items()}
        assert START < len(finished) < BUDGET, "the kill did not come mid-batch:\n" + killed_log[-3000:]
        assert running, "no batch case was simulating at the kill:\n" + killed_log[-3000:]
        # YADE runs in a session of its own: it must die with its launcher, not run on orphaned
        deadline = time.monotonic() + 3
        while yade_runs(wf) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not yade_runs(wf), f"YADE runs outlived the kill -9: {yade_runs(wf)}"
    finally:
        kill_leftovers(wf)
    kept_steps = {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in steps.glob("step_*.json")}
    assert set(kept_steps) == {f"step_{START}.json"}
    print(f"\n[faults] killed after {time.monotonic() - started:.0f} s: {len(finished)} of {BUDGET} cases finished, "
          f"{len(running)} simulating")

    assert snakemake(wf, "--unlock").returncode == 0  # kill -9 leaves Snakemake's lock (README)
    resumed_at = time.monotonic()
    run = snakemake(wf, "converge")  # the same command
    output = run.stdout + run.stderr
    assert run.returncode == 0, output[-6000:]
    print(f"[faults] the resume took {time.monotonic() - resumed_at:.0f} s")

    after = raw_files(wf)
    assert len(after) == BUDGET  # none lost
    simulated, reused = simulated_and_reused(output)
    for cid, data in finished.items():  # none run again: the same raw record, YADE's result never rewritten
        sim = after[cid].with_name("simulated.json")
        assert after[cid].read_bytes() == data and (sim.read_bytes(), sim.stat().st_mtime_ns) == results[cid], cid
        # a raw record written again is a case killed after its YADE run ended but before Snakemake
        # recorded the job: re-planned, it re-used the simulation (scripts/run_case.py says so)
        assert after[cid].stat().st_mtime_ns == raw_times[cid] or cid in reused, cid
    for name, (data, mtime) in kept_steps.items():  # the step before the batch is not re-decided
        assert (steps / name).read_bytes() == data and (steps / name).stat().st_mtime_ns == mtime, name
    assert not set(simulated) & set(finished), "a finished case was simulated again"
    assert len(simulated) == len(set(simulated)), simulated  # each unfinished case simulated once
    # the rest: simulated now, or (killed between YADE's end and Snakemake's bookkeeping) re-used
    assert set(after) - set(finished) <= set(simulated) | set(reused), (simulated, reused)
    assert set(reused) <= had_result, f"re-used a simulation finished after the kill (an orphaned YADE): {reused}"
    print(f"[faults] the resume simulated {len(simulated)} cases, re-used {len(reused)} finished simulations")

    assert_same_table(read_rows(steps / "table.csv"), read_rows(uninterrupted / "results" / "converge" / "table.csv"))
    got, expected = (json.loads((w / "results" / "converge" / "stopped.json").read_text()) for w in (wf, uninterrupted))
    assert (got["n"], got["reason"]) == (expected["n"], expected["reason"]) == (BUDGET, "case budget")


def test_a_killed_yade_run_is_retried_and_nothing_else_is_lost(uninterrupted, tmp_path):
    """`kill -9` of one YADE run while it simulates (the loop's first two cases, as an LDS sweep of
    2): the launcher records the crash with the exit code and its log, Snakemake retries it once,
    the same run finishes it; the other case runs once; both give the uninterrupted run's metrics
    to the last digit, and nothing is left to do."""
    wf = make_workflow(tmp_path, TINY_LOOP, DROP)
    target = "results/tables/lds.csv"
    log_path = tmp_path / "run.log"
    started = time.monotonic()
    victim = None
    with open(log_path, "w") as log:
        proc = subprocess.Popen([SNAKEMAKE, target], cwd=wf, stdin=subprocess.DEVNULL, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
        try:
            deadline = time.monotonic() + 300
            while victim is None and proc.poll() is None and time.monotonic() < deadline:
                for pid, cid in yade_runs(wf).items():
                    case_log = wf / "results" / "cases" / cid / "run.log"
                    # the scene is built, the run under way
                    if case_log.exists() and "start:" in case_log.read_text(errors="replace"):
                        os.kill(pid, signal.SIGKILL)  # kill -9 of this one YADE run only
                        victim = cid
                        break
                time.sleep(0.05)
            code = proc.wait(timeout=300)
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            kill_leftovers(wf)
    output = log_path.read_text(errors="replace")
    print(f"\n[faults] the run with a killed YADE took {time.monotonic() - started:.0f} s")
    assert victim, "no YADE run was caught simulating:\n" + output[-3000:]
    assert code == 0, output[-6000:]
    # the crash is named with YADE's exit code and where its log is, and retried
    assert re.search(rf"{victim}: yade exited with code -9 \(crashed\).*\(log: results/cases/{victim}/run\.log\) "
                     r"\(attempt 1; will be retried\)", output), output[-6000:]
    simulated, reused = simulated_and_reused(output)
    cases = sorted(raw_files(wf))
    assert len(cases) == 2 and victim in cases
    assert sorted(simulated) == cases and not reused  # each case simulated to the end once: the victim on its retry
    table = read_rows(wf / target)
    assert sorted(r["case_id"] for r in table) == cases  # one row each, no other
    assert all(r["status"] == "ok" for r in table), [(r["case_id"], r["status"], r["reason"]) for r in table]
    for cid in cases:  # the uninterrupted loop's first two cases, to the last digit
        got, expected = (json.loads((w / "results" / "cases" / cid / "metrics.json").read_text())
                         for w in (wf, uninterrupted))
        assert same_record(got, expected), cid
    assert planned_jobs(snakemake(wf, target, "-n").stdout) == {}  # nothing left to do
