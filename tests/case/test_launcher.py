"""What the launcher makes of a run that produced no result: whether it is retried, and the reason
that reaches the results table and the run summary. The logs below are what Debian's YADE
2023.02a wrote for a refused case (captured from a real run) and a crashed one."""
import re

import pandas as pd
import pytest
from conftest import ROOT

from spreadmap.case.identity import case_scene
from spreadmap.case.launcher import failure_reason, failure_record, retry_wanted
from spreadmap.metrics import case_metrics
from spreadmap.run_report import run_summary, summary_text
from spreadmap.table import build_table

POINT = {"f": 0.3, "d_um": 10.0, "h_um": 60.0, "v_mm_s": 10.0}
REFUSAL = ("REFUSED: time_step 3.374e-06 s is above the Rayleigh critical step 1.687e-06 s of this case "
           "(d = 10.0 um, density 7980000 kg/m3); lower it below the critical step.")
# YADE's banner line ends in a space: written \x20 below, so the logs stay verbatim without trailing whitespace
REFUSED_LOG = f"""$ /usr/bin/yade -n -j1 -x /tmp/case.py /tmp/raw.json
Welcome to Yade 2023.02a\x20
Using python version: 3.11.2 (main, Apr 28 2025, 14:11:48) [GCC 12.2.0]
TCP python prompt on localhost:9001, auth cookie `akueys'
XMLRPC info provider on http://localhost:21001
Running script /tmp/case.py
[smoke-f0.3000-d10.000-h60.000-v10.0000-s1] {REFUSAL}
"""
CRASHED_LOG = """$ /usr/bin/yade -n -j1 -x /tmp/case.py /tmp/raw.json
Welcome to Yade 2023.02a\x20
Running script /tmp/case.py
[smoke-f0.3000-d10.000-h60.000-v10.0000-s1] start: 404 spheres
Traceback (most recent call last):
  File "/tmp/case.py", line 200, in <module>
MemoryError: std::bad_alloc
"""


def failed_run(tmp_path, config, log_text, code, outcome):
    _, params = case_scene(POINT, "smoke", config, 1)
    log = tmp_path / "run.log"
    log.write_text(log_text)
    result = {"exit_code": code, "outcome": outcome, "wall_time": 2.5,
              "reason": failure_reason(code, outcome, log)}
    return params, result, log


def test_a_refused_case_is_recorded_at_once_with_its_verdict(tmp_path, config):
    params, result, log = failed_run(tmp_path, config, REFUSED_LOG, 2, "refused")
    assert not retry_wanted(result, attempt=1, retries=1)  # deterministic: a retry would refuse again
    raw = failure_record(params, result, log)
    assert raw["status"] == "refused" and REFUSAL in raw["reason"] and str(log) in raw["reason"]
    assert REFUSAL in raw["log_tail"]

    # the reason reaches the results table and the run summary, not only the raw record
    metrics = tmp_path / "metrics.json"
    metrics.write_text(pd.Series(case_metrics(raw, config["regime"], config["stability"], config["metrics"])).to_json())
    table = build_table([metrics], [tmp_path / "missing.tsv"], [{"sweep": "points", "index": 0}])
    assert table.loc[0, "status"] == "refused" and REFUSAL in table.loc[0, "reason"]
    summary = run_summary({"points": table}, config["regime"])
    assert summary["sets"]["points"]["failed"] == 1 and summary["sets"]["points"]["usable"] == 0
    assert REFUSAL in summary["sets"]["points"]["problems"][0]["reason"]
    assert f"{params['case_id']}: refused: yade exited with code 2 (refused): {REFUSAL}" in summary_text(summary)


def test_a_crash_is_retried_once_then_recorded_with_the_error_line(tmp_path, config):
    params, result, log = failed_run(tmp_path, config, CRASHED_LOG, 1, "crashed")
    assert retry_wanted(result, attempt=1, retries=1) and not retry_wanted(result, attempt=2, retries=1)
    raw = failure_record(params, result, log)
    assert raw["status"] == "failed"
    assert raw["reason"] == f"yade exited with code 1 (crashed): MemoryError: std::bad_alloc (log: {log})"


@pytest.mark.parametrize("outcome, retried", [("timeout", True), ("crashed", True), ("refused", False),
                                              ("failed", False)])
def test_only_what_may_not_recur_is_retried(outcome, retried):
    """A timeout or a crash may not recur (a busy machine, a killed process); the YADE script's own
    verdicts (refused before running, a failed check such as a cloud too dense) would."""
    assert retry_wanted({"outcome": outcome}, attempt=1, retries=1) is retried


def test_a_timeout_says_where_the_run_was(tmp_path):
    log = tmp_path / "run.log"
    log.write_text("[c] progress phase=move t=0.0504 s steps=33200\n\n[launcher] timed out after 2 s wall time\n")
    reason = failure_reason(None, "timeout", log, timeout_s=2.0)
    assert reason.startswith("timed out after 2 s wall time (outer timeout); killed: progress phase=move t=0.0504 s")


@pytest.mark.faults
def test_a_killed_launcher_takes_its_yade_run_with_it(tmp_path):
    """YADE runs in a session of its own (the outer timeout kills its group), out of reach of a
    `kill -9` of the workflow's process group: it must die with the launcher that started it, not
    run on orphaned beside the resumed run of the same case. A stand-in `yade` (SPREADMAP_YADE)
    that prints its pid and sleeps; the launcher's process is killed with SIGKILL."""
    import os
    import signal
    import subprocess
    import sys
    import time

    fake = tmp_path / "yade"
    fake.write_text("#!/bin/sh\necho \"stand-in yade pid $$\"\nexec sleep 60\n")
    fake.chmod(0o755)
    code = ("import sys; from spreadmap.case.launcher import run_case; "
            "run_case(sys.argv[1], sys.argv[2], sys.argv[3], 60)")
    env = {**os.environ, "SPREADMAP_YADE": str(fake), "PYTHONPATH": str(ROOT)}
    log = tmp_path / "run.log"
    launcher = subprocess.Popen([sys.executable, "-c", code, str(tmp_path / "case.py"), str(tmp_path / "raw.json"), str(log)],
                                env=env, stdin=subprocess.DEVNULL, start_new_session=True)
    pid = None
    try:
        deadline = time.monotonic() + 30
        while pid is None and time.monotonic() < deadline:
            found = re.search(r"stand-in yade pid (\d+)", log.read_text()) if log.exists() else None
            pid = int(found.group(1)) if found else time.sleep(0.05)
        assert pid, "the stand-in yade did not start"
        os.kill(launcher.pid, signal.SIGKILL)
        launcher.wait()
        deadline = time.monotonic() + 5
        while alive(pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not alive(pid), f"yade (pid {pid}) outlived its launcher"
        assert "--pdeathsig KILL" in log.read_text().splitlines()[0]  # the log's first line: what was run
    finally:
        for p in (launcher.pid, pid):
            if p and alive(p):
                os.kill(p, signal.SIGKILL)


def alive(pid: int) -> bool:
    """Whether pid runs (a zombie, dead but not yet reaped, does not count)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
