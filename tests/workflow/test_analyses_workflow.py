"""The analysis half of the DAG on a small finished smoke run: convergence, surrogate, maps,
case pictures, VTK, the HTML report, and the run-until-converged target.

The run's DEM cases are published (tests/data/analyses_run: the loop's cases and the lattice's, as
the workflow's own tables) and restored into the workflow copy (tools/restore_study.py's code), so
the analyses run on real smoke cases without running them again: only the picture point's case runs
YADE (its picture and VTK need a raw record). A change of the scene or of this config re-keys the
cases; the fixture then says so and how to publish them again:

    SPREADMAP_REPUBLISH=1 .venv/bin/python -m pytest -q tests/workflow/test_analyses_workflow.py
"""
import copy
import hashlib
import json
import os
import re
import shutil

import pytest
from conftest import FAST_SWEEP, ROOT, deep_update, make_workflow, planned_jobs, snakemake, write_config

from spreadlab.study.checksums import write_manifest
from spreadlab.study.restore import restore_cases, restore_time

pytestmark = pytest.mark.yade

SMALL_RUN = deep_update(copy.deepcopy(FAST_SWEEP), {
    # the LDS sweep's 8 cases are the converge run's 8 LDS cases (the start's 4 and one or two of
    # each batch of 2: one LDS sequence, seed 42), re-used, not run again
    "sweeps": {"lds": {"seed": 42, "partitions": [4, 8]}, "lattice": {"k": [2]}},
    # blade speeds 10-15 mm/s: a smoke case's move at 5 mm/s is three times the steps of one at
    # 15, and the lattice's 16 corners and the loop's points are what this fixture's time is
    "ranges": {"d_um": {"min": 40, "max": 50}, "f": {"min": 0.3, "max": 0.45}, "v_mm_s": {"min": 10, "max": 15}},
    "points": {"named": {"demo": {"f": 0.3, "d_um": 45.0, "h_um": 65.0, "v_mm_s": 10.0}}},
    "pictures": {"cases": ["demo"], "vtk": ["demo"]},
    # the surrogate's validation at its smallest that still chooses inside the folds (two MLP
    # penalties): one repeat of 3 folds (the shipped 3 x 5 with 12 MLP settings took 115 s here)
    "surrogate": {"neurons": [2, 4], "seeds": [0, 1, 2], "cv_folds": 3, "cv_repeats": 1, "gp_restarts": 0,
                  "ensemble_members": 2, "mlp_sizes": [4], "mlp_alphas": [0.1, 1.0]},
    "study_rule": {"sampling_study": {"seeds": 2, "k_max": 4}},
    "maps": {"sobol_n": 128, "sobol_draws": 8, "machine": {"n_h": 3, "n_v": 3}, "powder": {"v_mm_s": 12.0}},
    "decisions": {"machine": {"v_mm_s": [10, 15]}},  # the machine's limits inside the ranges above
    # 10 cases: the surrogate's 3-fold validation needs 8 usable, and a smoke case may be flagged
    # (and a tolerance no smoke run reaches: the loop runs to its budget)
    "converge": {"start": 4, "batch": 2, "k_consecutive": 3, "budget": 10,
                 "map_error": {"tolerance": {"mfr": 1e-4, "pd": 1e-4}}},
})
MAIN_FIGURES = ["path", "surrogate_parity", "surrogate_r2_vs_neurons", "surrogate_learning_curve", "machine_map",
                "powder_band_map", "powder_cluster_map", "parallel_coordinates", "regime_overlay",
                "sensitivity_ranking", "demo", "timeline", "machine_map_mlp", "powder_band_map_mlp"]
STUDY_FIGURES = ["distributions", "statistics", "sampling_study"]


PUBLISHED = ROOT / "tests" / "data" / "analyses_run"  # this fixture's DEM cases (the module's docstring)
PUBLISHED_TABLES = {"results/converge/table.csv": "cases_converge.csv", "results/tables/lattice.csv": "cases_lattice.csv"}
REPUBLISH = os.environ.get("SPREADMAP_REPUBLISH") == "1"
STALE = ("tests/data/analyses_run no longer holds this run's cases (a change of the scene or of SMALL_RUN re-keys "
         "them): publish them again with SPREADMAP_REPUBLISH=1 .venv/bin/python -m pytest -q "
         "tests/workflow/test_analyses_workflow.py, and commit tests/data/analyses_run")


def simulated(wf) -> set[str]:
    """The cases of a workflow copy that YADE ran (a restored case has no raw record)."""
    return {p.parent.name for p in (wf / "results" / "cases").glob("*/raw.json")}


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    wf = make_workflow(tmp_path_factory.mktemp("analyses"), SMALL_RUN, drop=("sweeps", "points"))
    if not REPUBLISH:
        restore_cases(sorted(PUBLISHED.glob("cases_*.csv")), wf, mtime=restore_time(wf))
    run = snakemake(wf, timeout=900)  # the main job: the converge run, its surrogate and maps
    assert run.returncode == 0, (run.stdout + run.stderr)[-5000:]
    planned = planned_jobs(snakemake(wf, "sweeps", "sampling", "-n").stdout)
    # the lattice's 2^4 (restored, or run to publish them): the LDS sweep's cases are the loop's
    assert planned.get("run_case", 0) == (16 if REPUBLISH else 0), (planned, STALE)
    sweeps = snakemake(wf, "sweeps", "sampling", timeout=900)  # the study's protocol beside it
    assert sweeps.returncode == 0, (sweeps.stdout + sweeps.stderr)[-5000:]
    ran = simulated(wf)
    if REPUBLISH:
        shutil.rmtree(PUBLISHED, ignore_errors=True)
        PUBLISHED.mkdir(parents=True)
        for source, name in PUBLISHED_TABLES.items():
            shutil.copy(wf / source, PUBLISHED / name)
        write_manifest(PUBLISHED, ["cases_*.csv"])
        assert len(ran) == 10 + 16 + 1, sorted(ran)  # the loop's, the lattice's and the picture point's
    else:
        # YADE ran the picture point's case, and no restored case again. The loop's LDS cases are
        # fixed by its seed and were restored (the lattice's dry run above says the publication is of
        # this scene); its two cases chosen by the model are the published ones where the fit is the
        # same to the bit (this machine: YADE ran the picture point alone), and may run here if
        # another machine's arithmetic leads the loop elsewhere.
        published = {line.split(",", 1)[0] for table in PUBLISHED.glob("cases_*.csv")
                     for line in table.read_text().splitlines()[1:]}
        assert not ran & published, sorted(ran & published)
        assert len(ran) <= 1 + 2, (sorted(ran), STALE)
        print(f"\n[analyses] YADE ran {len(ran)} of the run's {len(ran | published)} cases (the rest restored)")
    return wf


def test_main_job_writes_every_analysis_output(finished_run):
    wf = finished_run / "results"
    for stem in ["convergence/distributions", "convergence/statistics", "convergence/sampling_study",
                 "surrogate/surrogate_parity", "maps/machine_map", "maps/powder_band_map", "maps/powder_cluster_map",
                 "maps/parallel_coordinates", "maps/regime_overlay", "maps/sensitivity_ranking", "pictures/demo",
                 "converge/timeline", "maps/machine_map_mlp", "maps/powder_band_map_mlp"]:
        for ext in ("png", "pdf", "csv"):
            assert (wf / f"{stem}.{ext}").stat().st_size > 0, f"{stem}.{ext}"
    assert (wf / "maps" / "regime_overlay_plane.csv").stat().st_size > 0  # the regime figure's (d, h) plane
    # the run's timeline: its DEM cases on the cores, from this run's Snakemake log
    timeline = json.loads((wf / "converge" / "timeline.json").read_text())
    assert timeline["DEM_case_s"] > 0 and timeline["wall_s"] > 0 and timeline["lanes"] >= 1
    assert 0.0 <= timeline["idle_share"] < 1.0
    summary = json.loads((wf / "convergence" / "summary.json").read_text())
    assert {"lds", "lattice"} <= set(summary["sweeps"])
    # the main job's summary covers the converge run and the chosen points; the sweeps have their own
    assert set(json.loads((wf / "summary.json").read_text())["sets"]) == {"converge", "points"}
    assert set(json.loads((wf / "sweeps_summary.json").read_text())["sets"]) == {"lds", "lattice", "points"}
    ranking = (wf / "maps" / "sensitivity_ranking_table.csv").read_text()
    assert all(name in ranking for name in ("f", "d_um", "h_um", "v_mm_s"))
    # the model says which table it was trained on, by content: the file's SHA-256
    meta = json.loads((wf / "surrogate" / "model.json").read_text())
    source = finished_run / meta["source_path"]
    assert meta["source_path"].endswith("converge/table.csv")  # trained on the main job's converge run
    assert meta["source_sha256"] == hashlib.sha256(source.read_bytes()).hexdigest()
    assert meta["n_train"] + meta["n_test"] == meta["n_usable"] > 0
    # the MLP ensemble beside the map model (issue 52): an MLP for every target, on the same table
    mlp = json.loads((wf / "surrogate" / "model_mlp.json").read_text())
    assert set(mlp["map_model"].values()) == {"mlp"} and mlp["source_sha256"] == meta["source_sha256"]
    predictions = (wf / "surrogate" / "predictions.csv").read_text()
    assert {"mfr_model_sd", "mfr_run_sd"} <= set(predictions.splitlines()[0].split(","))
    # the decisions and the explorer page come with the main job
    recs = (wf / "decisions" / "recommendations.csv").read_text()
    assert "demo" in recs and (wf / "decisions" / "probability.png").stat().st_size > 0
    assert "<title>spreadmap explorer</title>" in (wf / "decisions" / "explorer.html").read_text(errors="replace")[:2000]


def test_vtk_written_when_asked(finished_run):
    files = {f.stem: f for f in (finished_run / "results" / "vtk" / "demo").glob("*.vtk")}
    assert set(files) == {"blade_start", "window_start", "window_middle", "window_end"}
    head = files["window_end"].read_text().splitlines()[:5]
    assert head[0].startswith("# vtk DataFile") and "POLYDATA" in head[3]


def test_report_contains_every_figure(finished_run):
    """The main job's report has its own figures; asked for with the study's targets, theirs too."""
    run = snakemake(finished_run, "--report", "report.html", timeout=600)
    assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
    html = (finished_run / "report.html").read_text(errors="replace")
    for name in MAIN_FIGURES:
        assert re.search(rf"{name}\.png", html), f"{name}.png missing from the report"
    assert not re.search(r"distributions\.png", html)  # a sweeps figure: not the main job's
    run = snakemake(finished_run, "--report", "everything.html", "all", "sweeps", "sampling", timeout=600)
    assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
    html = (finished_run / "everything.html").read_text(errors="replace")
    for name in MAIN_FIGURES + STUDY_FIGURES:
        assert re.search(rf"{name}\.png", html), f"{name}.png missing from the report"


def test_converge_stops_at_the_budget_when_the_criterion_never_holds(finished_run):
    # the main job ran the converge loop: asking for it again runs nothing
    dry = snakemake(finished_run, "converge", "-n")
    assert dry.returncode == 0 and "run_case" not in planned_jobs(dry.stdout), dry.stdout[-3000:]
    stopped = json.loads((finished_run / "results" / "converge" / "stopped.json").read_text())
    # 4, 6, 8, then 10 smoke cases: too few, or too noisy, for the map criteria; the run ends on its budget
    assert stopped["reason"] == "case budget" and stopped["n"] == 10


def test_converge_stops_early_when_the_criterion_holds_at_once(finished_run):
    # thresholds no map can miss: the CV RMSE and the CIs hold at the first step with enough cases
    cfg = deep_update(copy.deepcopy(SMALL_RUN), {"converge": {
        "start": 6, "budget": 12, "min_stop_cases": 0, "stop_on": ["cv_rmse", "ci"], "cv_rmse": {"factor": 1000.0},
        "ci": {"halfwidth": {"mean": 1000.0, "std": None, "median": None, "skewness": None, "kurtosis": None}}}})
    write_config(finished_run, cfg, drop=("sweeps", "points"))
    (finished_run / "results" / "converge").exists() and [
        p.unlink() for p in (finished_run / "results" / "converge").glob("*.json")]
    dry = snakemake(finished_run, "converge", "-n")
    assert "converge_step" in planned_jobs(dry.stdout)  # the dry run shows the first step
    run = snakemake(finished_run, "converge", timeout=600)
    assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
    stopped = json.loads((finished_run / "results" / "converge" / "stopped.json").read_text())
    assert stopped["reason"] == "criteria met" and stopped["n"] < 12


def test_the_study_publishes_and_answers_from_a_finished_run(finished_run, tmp_path):
    """tools/publish_study.py on a run with the main job and the sweeps: its cases tables are the
    workflow's own (the same cases and results), and summary.md answers every question from them."""
    import subprocess
    import sys

    import pandas as pd
    from conftest import ROOT

    from spreadlab.study.summary import NOT_YET

    out = tmp_path / "study"
    run = subprocess.run([sys.executable, str(ROOT / "tools" / "publish_study.py"), str(finished_run), "--out", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    for name in ("lds", "lattice"):
        ours = pd.read_csv(out / f"cases_{name}.csv")
        theirs = pd.read_csv(finished_run / "results" / "tables" / f"{name}.csv")
        assert list(ours["case_id"]) == list(theirs["case_id"]), name
        assert list(ours["mfr"]) == list(theirs["mfr"]), name
    text = (out / "summary.md").read_text()
    # every question answered but the held-out check (tools/heldout.py), which this run has not had
    heldout = "## The held-out check (points no sweep ran, predicted before they ran)\n" + NOT_YET
    assert heldout in text and text.count(NOT_YET) == 1, text
    assert "- lds: 8 of 8 cases finished" in text and "- lattice: 16 of 16 cases finished" in text
    assert "The main job's loop: the map criteria" in text
    assert "The study's rule (five statistics within 0.5 %), lds:" in text
    assert "The study's rule (five statistics within 0.5 %), lattice:" in text
    for target in ("mfr", "pd"):
        assert re.search(rf"- {target} \(gp, the maps\): CV RMSE [0-9.]+ \(interval", text), target
        assert f"The study's MLP protocol, {target}: R^2" in text
        assert re.search(rf"- {target}: (d_um|h_um|f|v_mm_s) [0-9.]+ \(", text), target
        for variable in ("v_mm_s", "f", "h_over_d"):
            assert f"- {target} vs {variable}: " in text, (target, variable)
    for variable in ("v_mm_s", "f", "h_over_d"):
        trend = pd.read_csv(out / f"trend_{variable}.csv").dropna(subset=["mfr"])  # h/d levels with no points: NaN
        assert len(trend) >= 3, variable
        assert ((trend["mfr_low"] <= trend["mfr"]) & (trend["mfr"] <= trend["mfr_high"])).all()
        assert (trend["mfr_high"] > trend["mfr_low"]).any()  # a trained model is unsure somewhere
    assert re.search(r"- normal: \d+ of \d+ cases; h/d", text)
