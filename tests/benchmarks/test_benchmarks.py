"""The scripts of benchmarks/ run and print what they promise, on tiny inputs: case_cost.py on two
smoke cases (real YADE), surrogate_speed.py on a tiny model trained here (and without a model),
main_job.py as a dry run only. About half a minute on a busy 2-core machine."""
from __future__ import annotations

import csv
import json
import re
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT, script_module

from spreadmap import design
from spreadmap import surrogate as S

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


def pooled_c(stdout: str, name: str = "mfr") -> tuple[float, float, float]:
    return tuple(map(float, re.search(rf"{name}: pooled c = (\S+), 90 % interval \[(\S+), (\S+)\]", stdout).groups()))


def test_counting_noise_of_the_default_scene_on_the_published_precision_cases():
    """The configured noise constant lies inside the pooled interval that the published seeds of
    the default scene (the precision benchmark's rough-substrate arms, each case's own count N) give."""
    r = run("counting_noise.py", "--cases", ROOT / "docs" / "precision" / "cases.csv", "--group", "arm", "point",
            "--arms", "physics", "precision", "precision_slow_settle", "window8", "shipped", timeout=120)
    assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
    configured = float(re.search(r"configured c \(metrics.counting_noise_c\): (\S+)", r.stdout).group(1))
    est, lo, hi = pooled_c(r.stdout)
    assert lo < est < hi and lo <= configured <= hi, r.stdout
    cells = int(re.search(r"\((\d+) rows, (\d+) cells\)", r.stdout).group(2))
    assert cells >= 16 and len(re.findall(r"Bartlett test", r.stdout)) == 2, r.stdout


def test_counting_noise_of_the_flat_floor_on_the_published_fidelity_study():
    """The study's flat floor (docs/fidelity_flat, fixed windows: N from the preset) has a larger c
    than the configured one, the reason the config says so."""
    r = run("counting_noise.py", timeout=120)
    assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
    configured = float(re.search(r"configured c \(metrics.counting_noise_c\): (\S+)", r.stdout).group(1))
    est, lo, hi = pooled_c(r.stdout)
    assert configured < lo < est < hi and "16 cells" in r.stdout, r.stdout


def test_layer_metrics_on_a_constructed_record(tmp_path):
    """Two simple cubic layers (gap 2 d) behind a blade that moved 10 d: the script prints the
    old and new metrics side by side; both MFRs are pi/6 here and the layer decomposes PD."""
    import json

    d = 30e-6
    xs, ys, zs = np.arange(0.5, 20, 1.0), np.arange(0.5, 4, 1.0), np.array([0.5, 1.5])
    end = np.array([(x, y, z) for x in xs for y in ys for z in zs]) * d
    start = end[end[:, 0] < 10 * d]
    snap = lambda p, x: {"positions": p.tolist(), "radii": [d / 2] * len(p), "blade_rear_x": x}  # noqa: E731
    raw = {"status": "ok", "peak_overlap_ratio": 0.01, "escaped_particles": 0,
           "params": {"case_id": "lattice", "preset": "smoke", "seed": 1, "diameter": d, "gap": 2 * d, "width": 4 * d,
                      "blade_thickness": 2 * d, "time_step": 1e-7, "critical_time_step": 4e-7, "density_scale": 1000.0,
                      "point": {"f": 0.3, "d_um": 30.0, "h_um": 60.0, "v_mm_s": 10.0}},
           "snapshots": {"window_start": snap(start, 10 * d), "window_end": snap(end, 20 * d)}}
    paths = []
    for i in range(3):
        (tmp_path / f"raw{i}.json").write_text(json.dumps(raw))
        paths.append(tmp_path / f"raw{i}.json")
    r = run("layer_metrics.py", *paths, "--csv", tmp_path / "out.csv", timeout=120)
    assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
    out = pd.read_csv(tmp_path / "out.csv")
    assert np.allclose(out["mfr"], np.pi / 6) and np.allclose(out["mfr_centres"], np.pi / 6)
    assert "layer_fill x thickness_ratio / PD: 1.00" in r.stdout and (out["regime"] == "normal").all()


def test_schedule_order_prints_the_known_makespans(tmp_path):
    """One 600 s case and ten of 60 s on 2 cores: the costliest first finishes at 600 s, the lower
    bound (10.0 min); a random order that starts the long case last can take up to 300 + 600 s."""
    table = tmp_path / "cases.csv"
    pd.DataFrame({"cpu_time": [60.0] * 10 + [600.0]}).to_csv(table, index=False)
    r = run("schedule_order.py", table, "--cores", "2", "--orders", "500")
    assert r.returncode == 0, r.stderr
    assert "costliest first: 10.0 min (lower bound 10.0)" in r.stdout
    worst = float(re.search(r"worst ([0-9.]+)", r.stdout).group(1))
    assert 10.0 < worst <= 15.0


def test_layer_noise_pools_the_seed_spread_within_points(tmp_path):
    """Two points x three seeds of a two-layer simple cubic bed (as above) with a seeded share of
    the top layer's spheres removed: the script's SD over seeds is the pooled within-point SD
    (sum of squares about each point's mean / (6 - 2)), checked here from the measures of the
    same records, and its stated SD the root mean square of the cases' own SDs."""
    import json

    from spreadmap import config as spreadmap_config
    from spreadmap.metrics import measure

    d = 30e-6
    xs, ys, zs = np.arange(0.5, 20, 1.0), np.arange(0.5, 4, 1.0), np.array([0.5, 1.5])
    full = np.array([(x, y, z) for x in xs for y in ys for z in zs]) * d
    snap = lambda p, x: {"positions": p.tolist(), "radii": [d / 2] * len(p), "blade_rear_x": x}  # noqa: E731
    rng = np.random.default_rng(4)
    paths = []
    for point, share in (("a", 0.2), ("b", 0.5)):
        for seed in (1, 2, 3):
            keep = (full[:, 2] < d) | (rng.random(len(full)) > share)
            end = full[keep]
            raw = {"status": "ok",
                   "params": {"diameter": d, "gap": 2 * d, "width": 4 * d, "blade_thickness": 2 * d},
                   "snapshots": {"window_start": snap(end[end[:, 0] < 10 * d], 10 * d), "window_end": snap(end, 20 * d)}}
            path = tmp_path / f"{point}-s{seed}" / "raw.json"
            path.parent.mkdir()
            path.write_text(json.dumps(raw))
            paths.append(path)
    r = run("layer_noise.py", *paths, "--csv", tmp_path / "out.csv", timeout=120)
    assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
    out = pd.read_csv(tmp_path / "out.csv").set_index("measure")
    settings = spreadmap_config.load(ROOT / "config.yaml")["metrics"]
    rows = pd.DataFrame([{"point": p.parent.name[0], **measure(json.loads(p.read_text()), settings)} for p in paths])
    for m in ("roughness_d", "thickness_ratio", "layer_fill"):  # (the bottom layer covers the floor: coverage 1)
        ss = sum(((g - g.mean()) ** 2).sum() for _, g in rows.groupby("point")[m])
        assert out.loc[m, "dof"] == 4
        assert out.loc[m, "seed_sd"] == pytest.approx(np.sqrt(ss / 4), rel=1e-9) and out.loc[m, "seed_sd"] > 0
        assert out.loc[m, "stated_sd"] == pytest.approx(np.sqrt(np.mean(rows[f"{m}_sd"] ** 2)), rel=1e-9)
        assert out.loc[m, "seed_sd_low"] < out.loc[m, "seed_sd"] < out.loc[m, "seed_sd_high"]


def test_cost_map_summary_on_a_hand_made_table():
    """Four cases of 1, 2, 3 and 100 s at h/d 1, 2, 3, 4: mean 26.5, median 2.5, max / median 40,
    103 of the 106 s (and half the cases) at h/d >= 3."""
    cost_map = script_module("benchmarks/cost_map.py")

    s = cost_map.summary(np.array([1.0, 2.0, 3.0, 100.0]), np.array([1.0, 2.0, 3.0, 4.0]))
    assert s["mean"] == pytest.approx(26.5) and s["median"] == pytest.approx(2.5)
    assert s["max_over_median"] == pytest.approx(40.0)
    assert s["share_cpu_wide"] == pytest.approx(103 / 106) and s["share_cases_wide"] == pytest.approx(0.5)


def test_cost_map_anchors_two_scenes_to_their_measured_cases(tmp_path):
    """Two arms that are the same tree, whose measured cases differ by exactly 2x in CPU at every
    point: the anchored ratio of their mean cost over the box is 2 with a bootstrap interval of
    zero width, whatever the law's absolute seconds; every preset of the config is priced, with
    the points inside the config's box."""
    pts = [(0.3, 30, 65, 10), (0.45, 50, 55, 5), (0.3, 10, 75, 10)]
    measured = tmp_path / "cases.csv"
    with open(measured, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["arm", "point", "seed", "status", "f", "d_um", "h_um", "v_mm_s", "cpu_time"])
        for i, p in enumerate(pts):
            w.writerow(["slow", f"p{i}", 1, "ok", *p, 80.0 * (i + 1)])
            w.writerow(["fast", f"p{i}", 1, "ok", *p, 40.0 * (i + 1)])
    out = tmp_path / "map.json"
    r = run("cost_map.py", "--points", 16, "--measured", measured, "--arm", f"slow={ROOT}", "--arm", f"fast={ROOT}",
            "--boot", 200, "--json", out)
    assert r.returncode == 0, r.stderr
    import json

    result = json.loads(out.read_text())
    assert result["mean_ratio"]["ratio"] == pytest.approx(2.0)
    assert result["mean_ratio"]["ci95"] == pytest.approx([2.0, 2.0])
    presets = {row["preset"] for row in result["rows"] if row["arm"] == "slow"}
    assert {"smoke", "fast", "default", "reference"} <= presets
    law = [row for row in result["rows"] if row["scale"] == "law" and row["preset"] == "default"]
    assert law[0]["mean"] == pytest.approx(law[1]["mean"])  # the same tree plans the same cases
    assert 0 < law[0]["median"] <= law[0]["p90"] <= law[0]["max"]


@pytest.mark.parametrize("script, args, written", [
    ("noisy_study.py", ["--methods", "lds", "lattice", "--noises", "mult7", "--targets", "0.05"],
     ["noisy_study_runs.csv", "noisy_study_summary.csv", "noisy_study_rmse.csv", "noisy_study.png"]),
    ("cost_study.py", ["--targets", "0.05"],
     ["cost_study_runs.csv", "cost_study_needed.csv", "cost_study_summary.csv", "cost_study.png"])])
def test_sampling_studies_run_from_benchmarks(tmp_path, script, args, written):
    """The noisy and cost sampling studies (spreadlab.experiments) at their smallest: one seed, the
    LDS start only; every table and the figure written, the command recorded."""
    r = run(script, "--out", tmp_path, "--seeds", 1, "--n-max", 32, "--n-candidates", 128, *args, timeout=120)
    assert r.returncode == 0, r.stderr[-3000:]
    for name in written:
        assert (tmp_path / name).stat().st_size > 0, name
    meta = json.loads((tmp_path / script.replace(".py", "_run.json")).read_text())
    assert meta["command"].startswith(f"benchmarks/{script} --out ")
