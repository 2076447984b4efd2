"""The scripts of benchmarks/ run and print what they promise, on tiny inputs: case_cost.py on two
smoke cases (real YADE), surrogate_speed.py on a tiny model trained here (and without a model),
main_job.py as a dry run only. About half a minute on a busy 2-core machine."""
from __future__ import annotations

import csv
import re
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from spreadmap import design
from spreadmap import surrogate as S

from conftest import ROOT

BENCH = ROOT / "benchmarks"
PYTHON = str(ROOT / ".venv" / "bin" / "python") if (ROOT / ".venv" / "bin" / "python").exists() else sys.executable


def run(script: str, *args, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([PYTHON, str(BENCH / script), *map(str, args)], cwd=ROOT, capture_output=True, text=True,
                          timeout=timeout)


@pytest.mark.yade
def test_case_cost_two_smoke_cases(tmp_path):
    out = tmp_path / "cost.csv"
    # the cheapest point at smoke: ~130 spheres, a few CPU seconds per case
    r = run("case_cost.py", "--points", "low_friction_fast", "--presets", "smoke", "--seeds", 1, 2,
            "--workers", 2, "--csv", out)
    assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
    assert "preset smoke" in r.stdout
    assert "cores:" in r.stdout and "cpu:" in r.stdout
    with open(out) as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2
    assert {row["seed"] for row in rows} == {"1", "2"}
    for row in rows:
        wall, cpu = float(row["wall_time"]), float(row["cpu_time"])
        assert row["outcome"] == "ok" and row["preset"] == "smoke"
        assert 0 < cpu <= wall * 1.05 + 1.5, row
        assert float(row["particle_steps_per_cpu_s"]) > 0
        assert 0 <= float(row["mfr"]) <= 1 and 0 <= float(row["pd"]) <= 1


def test_case_cost_refuses_unknown_point():
    r = run("case_cost.py", "--points", "nowhere", "--presets", "smoke", timeout=60)
    assert r.returncode != 0 and "nowhere" in r.stderr


def tiny_model(path):
    """A surrogate fitted the package's way (fit_surrogate, save_model) on 40 synthetic cases."""
    rng = np.random.default_rng(0)
    u = rng.random((40, len(design.NAMES)))
    table = pd.DataFrame(design.to_physical(u), columns=list(design.NAMES))
    table.insert(0, "case_id", [f"tiny-{i}" for i in range(len(table))])
    table["status"], table["flagged"] = "ok", False
    table["mfr"] = 0.5 - 0.3 * u[:, 0] + 0.1 * u[:, 2]
    table["pd"] = 0.6 - 0.1 * u[:, 1]
    result = S.fit_surrogate(table, dict(neurons=[4], seeds=[0], cv_folds=2, cv_repeats=1, learning_curve=False,
                                         mlp_sizes=[2], mlp_alphas=[1.0], ensemble_members=2, gp_restarts=0),
                             log=lambda *a: None)
    S.save_model(result.model, path)
    return path


def test_surrogate_speed_on_a_tiny_model(tmp_path):
    model = tiny_model(tmp_path / "model.joblib")
    r = run("surrogate_speed.py", "--model", model, "-n", 2000, "--calls", 20, "--repeat", 2, timeout=120)
    assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
    rates = re.findall(r"predictions / s\s+best\s+(\S+)\s+median\s+(\S+)", r.stdout)
    latency = re.findall(r"latency per call\s+best\s+(\S+) ms\s+median\s+(\S+) ms", r.stdout)
    assert rates and latency, r.stdout
    best, med = map(float, rates[0])
    assert best >= med > 0
    best, med = map(float, latency[0])
    assert 0 < best <= med


def test_surrogate_speed_without_a_model(tmp_path):
    r = run("surrogate_speed.py", "--model", tmp_path / "missing.joblib", timeout=60)
    assert r.returncode != 0
    message = r.stderr.strip()
    assert len(message.splitlines()) == 1 and "snakemake --cores 2" in message, message


def test_main_job_dry_run(tmp_path):
    wf = tmp_path / "wf"
    r = run("main_job.py", "--dry-run", "--workdir", wf, "--config", "preset=smoke", timeout=180)
    assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
    planned = re.search(r"run_case jobs planned: (\d+)", r.stdout)
    assert planned and int(planned.group(1)) > 0, r.stdout
    assert re.search(r"^\s+render_case\s+\d+$", r.stdout, re.M)
    assert (wf / "Snakefile").is_file() and not (wf / "results").exists()


def test_main_job_refuses_a_used_workdir(tmp_path):
    (tmp_path / "something").write_text("x")
    r = run("main_job.py", "--dry-run", "--workdir", tmp_path, timeout=60)
    assert r.returncode != 0 and "not empty" in r.stderr
