"""Run a rendered case script with Debian's YADE, kept away from the project's venv.

YADE runs its own system Python: VIRTUAL_ENV, PYTHONPATH and PYTHONHOME are cleared and the venv
is taken off PATH; one thread (-j1, OMP_NUM_THREADS=1) because two single-threaded cases at once
beat one case on two threads. An outer timeout kills the whole process group: a blown-up run can
hang inside YADE, out of reach of the in-run watchdog. YADE runs in a session of its own (so that
the timeout can kill its group), which a `kill -9` of the workflow's process group does not reach:
it is therefore started under `setpriv --pdeathsig KILL` and dies with the launcher that started it,
instead of running on, orphaned, beside the resumed workflow's run of the same case."""
from __future__ import annotations

import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

from ..files import atomic_path, write_text_atomically
from ..records import CorruptFileError, read_raw

# Exit codes of yade_scripts/spreading_case.py. Its own verdicts (refused before running, failed a
# check, blown up) are deterministic: the same case gives the same verdict. Any other code is a
# crash ("crashed"), which like a timeout may not recur and is worth another attempt.
EXIT_CODES = {0: "ok", 2: "refused", 3: "blown", 4: "failed"}
RETRIED_OUTCOMES = ("crashed", "timeout")


def yade_executable() -> str:
    exe = os.environ.get("SPREADMAP_YADE") or shutil.which("yade", path=clean_environment()["PATH"])
    if not exe:
        raise FileNotFoundError("Debian's `yade` is not on PATH: run `bash tools/setup.sh` (apt-get install yade)")
    return exe


def die_with_parent() -> list[str]:
    """The prefix that makes YADE get SIGKILL when the process that started it dies (util-linux's
    setpriv, in every Debian: prctl PR_SET_PDEATHSIG, kept across its exec of yade); none where
    setpriv is missing."""
    setpriv = shutil.which("setpriv", path=clean_environment()["PATH"] + os.pathsep + "/usr/bin:/bin")
    return [setpriv, "--pdeathsig", "KILL", "--"] if setpriv else []


def clean_environment() -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME", "CONDA_PREFIX", "PYTHONSTARTUP")}
    venv_bins = {str(Path(sys.prefix) / "bin"), os.environ.get("VIRTUAL_ENV", "") + "/bin"}
    env["PATH"] = os.pathsep.join(p for p in os.environ.get("PATH", "").split(os.pathsep) if p and p not in venv_bins)
    env["OMP_NUM_THREADS"] = "1"
    env.setdefault("HOME", "/tmp")
    return env


def run_case(script: Path | str, raw_out: Path | str, log_path: Path | str, timeout_s: float) -> dict:
    """Run one case with Debian's YADE; returns the launcher result.

    YADE runs as ``yade -n -j1 -x <script> <raw_out>`` in raw_out's folder, with the venv kept out of
    its environment, in a session of its own and under ``setpriv --pdeathsig KILL`` where setpriv
    exists (see the module docstring). At the timeout the whole process group is killed. The raw
    result (written by the YADE script itself, atomically) exists after outcomes "ok" and "blown";
    an exit code that says "ok" or "blown" without it is a crash.

    Parameters
    ----------
    script : pathlib.Path or str
        The rendered case script (``spreadmap.case.render.render``).
    raw_out : pathlib.Path or str
        Where the YADE script writes its raw result; its folder is created and YADE runs in it.
    log_path : pathlib.Path or str
        The case's log (its folder created, the file overwritten): the command line, then YADE's
        output, then the launcher's line on a timeout.
    timeout_s : float
        The outer wall-time limit [s].

    Returns
    -------
    dict
        ``exit_code`` (int; None after a timeout), ``outcome`` ("ok", "refused", "blown", "failed",
        "crashed" or "timeout"; ``EXIT_CODES``), ``wall_time`` [s], ``cpu_time`` [s] (the user and
        system CPU of the finished child processes during the run) and ``reason`` ("" after "ok" and
        "blown", else one line: what happened, the log's verdict and where the log is;
        ``failure_reason``).

    Raises
    ------
    FileNotFoundError
        If Debian's ``yade`` is neither named by ``SPREADMAP_YADE`` nor on the PATH without the venv.
    """
    script, raw_out, log_path = Path(script), Path(raw_out), Path(log_path)
    raw_out.parent.mkdir(parents=True, exist_ok=True)
    log_path.parent.mkdir(parents=True, exist_ok=True)
    cmd = [*die_with_parent(), yade_executable(), "-n", "-j1", "-x", str(script.resolve()), str(raw_out.resolve())]
    start = time.time()
    cpu_start = resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(log_path, "w") as log:
        log.write("$ " + " ".join(cmd) + "\n")
        log.flush()
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                env=clean_environment(), cwd=str(raw_out.parent), start_new_session=True)
        try:
            code = proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            code = None
            log.write(f"\n[launcher] {failure_head(code, 'timeout', timeout_s)}\n")
    outcome = "timeout" if code is None else EXIT_CODES.get(code, "crashed")
    if outcome in ("ok", "blown") and not raw_out.exists():
        outcome = "crashed"
    reason = "" if outcome in ("ok", "blown") else failure_reason(code, outcome, log_path, timeout_s)
    cpu_end = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu_time = (cpu_end.ru_utime - cpu_start.ru_utime) + (cpu_end.ru_stime - cpu_start.ru_stime)
    return {"exit_code": code, "outcome": outcome, "wall_time": time.time() - start, "cpu_time": cpu_time,
            "reason": reason}


def finished_simulation(path: Path | str, params: dict) -> dict | None:
    """The raw record at `path` if it is a finished simulation of exactly these parameters.

    YADE writes its result (atomically) beside the workflow's declared output; a run killed after
    YADE finished but before Snakemake recorded the job as complete then resumes by re-using the
    result instead of simulating again. Any change of parameters invalidates it, and so does a
    damaged record (truncated, not a JSON object, not a raw record): the case runs again."""
    try:
        raw = read_raw(path)
    except (OSError, CorruptFileError):
        return None
    return raw if raw.get("status") in ("ok", "blown") and raw.get("params") == params else None


def simulate(params: dict, script: Path | str, raw_out: Path | str, log_path: Path | str) -> dict:
    """Run the case unless a finished simulation of the same parameters is already on disk.

    Either way the raw record ends up at raw_out (atomically). The simulation is written to
    ``simulated.json`` beside raw_out and re-used when it is a finished simulation (status "ok" or
    "blown") of exactly these parameters (``finished_simulation``); after a run that finished, the
    record gets the run's ``cpu_time`` [s] (the cost of the case). raw_out is a copy of it after
    outcomes "ok" and "blown" only.

    Parameters
    ----------
    params : dict
        The case's parameters (``spreadmap.case.identity.case_scene``), as the script was rendered
        with; ``timeout_s`` [s] is the run's outer timeout.
    script : pathlib.Path or str
        The rendered case script.
    raw_out : pathlib.Path or str
        Where the raw record ends up.
    log_path : pathlib.Path or str
        The case's log (written only when YADE runs).

    Returns
    -------
    dict
        The launcher result (``run_case``) with ``reused`` (bool). A re-used simulation: exit_code
        0, outcome the record's status, wall_time 0.0, a reason naming the file re-used, no
        ``cpu_time``.

    Raises
    ------
    FileNotFoundError
        If the case has to run and Debian's ``yade`` is not found (``run_case``).
    """
    raw_out = Path(raw_out)
    simulated = raw_out.with_name("simulated.json")
    reused = finished_simulation(simulated, params)
    if reused is not None:
        result = {"exit_code": 0, "outcome": reused["status"], "wall_time": 0.0,
                  "reason": f"re-used the finished simulation in {simulated}", "reused": True}
    else:
        result = run_case(script, simulated, log_path, params["timeout_s"])
        result["reused"] = False
        if result["outcome"] in ("ok", "blown"):
            # the CPU time of the YADE process (one core): the cost of the case, far less
            # disturbed than its wall time by whatever else the machine runs
            record = json.loads(simulated.read_text())
            record["cpu_time"] = result["cpu_time"]
            write_json_atomically(simulated, record)
    if result["outcome"] in ("ok", "blown"):
        with atomic_path(raw_out) as tmp:
            shutil.copyfile(simulated, tmp)
    return result


def log_tail(log_path: Path | str, lines: int = 15) -> str:
    try:
        return "\n".join(Path(log_path).read_text(errors="replace").splitlines()[-lines:])
    except OSError:
        return ""


_CASE_PREFIX = re.compile(r"^\[[^\]]*\]\s*")


def log_verdict(log_path: Path | str) -> str:
    """The line of a case's log that says why it stopped: the YADE script's own verdict
    (REFUSED: / FAILED: ...), else the last line YADE wrote (a traceback's error, the last
    progress line before a timeout). Without the case id prefix; "" for an empty log."""
    lines = [line.strip() for line in log_tail(log_path, lines=200).splitlines()]
    lines = [line for line in lines if line and not line.startswith(("[launcher]", "$ "))]
    lines = [_CASE_PREFIX.sub("", line) for line in lines]
    verdicts = [line for line in lines if line.startswith(("REFUSED:", "FAILED:"))]
    return (verdicts or lines or [""])[-1]


def failure_head(exit_code: int | None, outcome: str, timeout_s: float | None = None) -> str:
    if outcome == "timeout":
        return f"timed out after {timeout_s:.0f} s wall time (outer timeout); killed"
    if outcome == "crashed" and exit_code in (0, 3):
        return f"yade exited {exit_code} but wrote no raw result"
    return f"yade exited with code {exit_code} ({outcome})"


def failure_reason(exit_code: int | None, outcome: str, log_path: Path | str, timeout_s: float | None = None) -> str:
    """One line for the tables and the run summary: what happened, the log's own verdict (why),
    and where the log is."""
    why = log_verdict(log_path)
    head = failure_head(exit_code, outcome, timeout_s)
    return f"{head}: {why} (log: {log_path})" if why else f"{head} (log: {log_path})"


def retry_wanted(result: dict, attempt: int, retries: int) -> bool:
    """Whether a run that produced no result is worth another attempt.

    A crash or a timeout may not recur (``RETRIED_OUTCOMES``); the YADE script's own verdicts
    (refused, failed) would.

    Parameters
    ----------
    result : dict
        The launcher result (``run_case`` or ``simulate``): its ``outcome``.
    attempt : int
        The attempt that gave it, counting from 1.
    retries : int
        How many attempts after the first are allowed.

    Returns
    -------
    bool
        True when the outcome is "crashed" or "timeout" and ``attempt <= retries``.
    """
    return result["outcome"] in RETRIED_OUTCOMES and attempt <= retries


def failure_record(params: dict, result: dict, log_path: Path | str) -> dict:
    """The raw record of a case that produced no result (refusal, failed check, crash, timeout).

    Status "refused" for a refusal, else "failed", with the reason and the log's tail.

    Parameters
    ----------
    params : dict
        The case's parameters, kept in the record.
    result : dict
        The launcher result (``run_case`` or ``simulate``).
    log_path : pathlib.Path or str
        The case's log.

    Returns
    -------
    dict
        ``format`` ("spreadmap-raw-1"), ``status``, ``reason`` (the result's reason, else its
        outcome), ``params``, ``wall_time`` [s], ``exit_code`` and ``log_tail`` (the log's last 15
        lines; "" when it cannot be read).
    """
    status = "refused" if result["outcome"] == "refused" else "failed"
    return {"format": "spreadmap-raw-1", "status": status, "reason": result["reason"] or result["outcome"],
            "params": params, "wall_time": result["wall_time"], "exit_code": result["exit_code"],
            "log_tail": log_tail(log_path)}


def write_json_atomically(path: Path | str, data: dict) -> None:
    """Write a record as JSON (indent 1) to a file, atomically and durably (spreadmap.files).

    Parameters
    ----------
    path : pathlib.Path or str
        The file; its folder is created if missing.
    data : dict
        The record (JSON-serialisable).

    Raises
    ------
    OSError
        If the write fails; the file is left as it was (``spreadmap.files.atomic_path``).
    """
    write_text_atomically(path, json.dumps(data, indent=1))
