"""The study's plan (spreadlab.study.cases) is the plan the workflow runs, and the published study
(docs/study/) holds the cases of that plan with the tables they recompute to."""
import copy
import json
import re

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT, make_workflow, snakemake

from spreadlab.study.cases import cpu_hours_to_go, finished_table, planned_sweeps, progress
from spreadmap import config as spreadmap_config
from spreadmap.case.identity import case_id, readable_id, readable_part
from spreadmap.design import NAMES
from spreadmap.sweeps import planned_cases
from spreadmap.table import usable

DOCS = ROOT / "docs" / "study"


def test_the_plan_is_the_workflows_plan(tmp_path):
    """The case ids the workflow's dry run would render for the sweeps (its registry in
    rules/common.smk, from planned_cases) are the planned ones, LDS and two lattices sharing their corners."""
    sweeps = {"lds": {"seed": 42, "partitions": [4, 9]}, "lattice": {"k": [2, 3]}}
    wf = make_workflow(tmp_path, {"sweeps": sweeps})
    plan = planned_sweeps(spreadmap_config.load(wf / "config.yaml"))
    assert [label["index"] for _, label in plan["lds"]] == list(range(9))
    assert len(plan["lattice"]) == 16 + 81
    ran = {}
    for name in ("lds", "lattice"):
        dry = snakemake(wf, "-n", "--cores", "1", f"results/tables/{name}.csv")
        assert dry.returncode == 0, dry.stderr[-2000:]
        ran[name] = set(re.findall(r"results/cases/([^/\s]+)/case\.py", dry.stdout))
    assert ran["lds"] == {cid for cid, _ in plan["lds"]}
    assert ran["lattice"] == {cid for cid, _ in plan["lattice"]}
    assert len(ran["lattice"]) == 81 + 16 - 2 ** 4  # the lattices share their 16 corners


def test_planned_cases_go_past_the_lds_sweep_for_the_converge_budget(config):
    """LDS points past the sweep are planned (for converge.budget) but not in the sweep; the sweep's
    points come first, as in planned_sweeps, and the lattices follow."""
    cfg = copy.deepcopy(config)
    cfg["sweeps"] = {"lds": {"seed": 42, "partitions": [4, 6], "preset": "smoke"}, "lattice": {"k": [2]}}
    cases = list(planned_cases(cfg, lds_points=10))
    lds = [c for c in cases if c.sweep == "lds"]
    assert [c.label for c in lds] == [{"index": i} for i in range(10)]
    assert [c.in_sweep for c in lds] == [True] * 6 + [False] * 4
    assert [c.sweep for c in cases] == ["lds"] * 10 + ["lattice"] * 16
    assert all(c.preset == "smoke" and c.point["index"] == c.label["index"] for c in lds)
    assert all(c.case_id == case_id(c.point, c.preset or cfg["preset"], cfg) for c in cases)
    plan = planned_sweeps(cfg)
    assert plan["lds"] == [(c.case_id, {"sweep": "lds", **c.label}) for c in lds[:6]]
    assert [cid for cid, _ in plan["lattice"]] == [c.case_id for c in cases if c.sweep == "lattice"]
    assert [c.case_id for c in planned_cases(cfg, lds_points=3)] == [c.case_id for c in cases if c.in_sweep]


def _metrics(cid: str, point: dict, preset: str, seed: int, status: str = "ok", cpu: float = 60.0) -> dict:
    return {"case_id": cid, **point, "preset": preset, "seed": seed, "status": status,
            "mfr": 0.4, "pd": 0.35, "regime": "normal", "flagged": False, "flag_reason": "", "reason": "", "cpu_time": cpu}


def test_the_finished_table_holds_the_finished_cases_in_plan_order(config, tmp_path):
    cfg = copy.deepcopy(config)
    cfg["sweeps"] = {"lds": {"seed": 42, "partitions": [6]}, "lattice": {"k": [2, 3]}}
    plan = planned_sweeps(cfg)
    finished = [plan["lds"][i] for i in (4, 1, 5)] + [plan["lattice"][0], plan["lattice"][17]]
    for cid, _ in finished:
        parts = dict(re.findall(r"-([fdhv])([0-9.]+)", cid))
        point = {"f": float(parts["f"]), "d_um": float(parts["d"]), "h_um": float(parts["h"]),
                 "v_mm_s": float(parts["v"])}
        case = tmp_path / "results" / "cases" / cid
        case.mkdir(parents=True, exist_ok=True)
        status = "failed" if cid == plan["lds"][5][0] else "ok"
        (case / "metrics.json").write_text(json.dumps(_metrics(cid, point, "default", 1, status, cpu=3600.0)))
        (case / "benchmark.tsv").write_text("s\th:m:s\tmax_rss\n10\t0:00:10\t200\n")
    lds = finished_table(tmp_path, plan["lds"])
    assert list(lds["index"]) == [1, 4, 5]
    assert list(lds["case_id"]) == [plan["lds"][i][0] for i in (1, 4, 5)]
    lattice = finished_table(tmp_path, plan["lattice"])
    # lattice point 0 of k=2 (all minima) is also point 0 of k=3: one case, two rows
    assert plan["lattice"][16][0] == plan["lattice"][0][0]
    assert list(lattice["index"]) == [0, 16, 17] and list(lattice["k"]) == [2, 3, 3]
    done = progress(plan, {"lds": lds, "lattice": lattice}).set_index("sweep")
    assert done.loc["lds"].to_dict() == {"planned": 6, "finished": 3, "ok": 2, "failed": 1, "cpu_hours": 3.0}
    assert done.loc["lattice", "planned"] == 16 + 81 - 16 and done.loc["lattice", "finished"] == 2
    assert done.loc["lattice", "cpu_hours"] == 2.0  # the shared case counted once


def test_cpu_to_go_is_the_plans_cost_at_this_machines_speed(config):
    """The known truth: every case costs the planned-cost law times a machine factor 1.7 (with a
    log-normal scatter of SD 0.2 on the finished ones); with 48 of 81 LDS cases finished, the
    CPU to go is the law's sum over the other 33 (computed here from the scene's planned spheres
    and steps and the law's formula) times the factor, within the scatter's median error; with
    no case finished, the law uncalibrated."""
    from spreadmap.case.scene import scene_parameters
    from spreadmap.design import NAMES
    from spreadmap.loop.cost import DEFAULT_LAW

    cfg = copy.deepcopy(config)
    cfg["sweeps"] = {"lds": {"seed": 42, "partitions": [81]}, "lattice": {"k": [3]}}
    cases = list(planned_cases(cfg))
    lds = [c for c in cases if c.sweep == "lds"]

    coef = {**DEFAULT_LAW, **(cfg["converge"].get("cost_law") or {})}

    def law(cs):
        out = []
        for c in cs:
            p = scene_parameters(c.point, cfg["preset"], cfg, "x")
            out.append(np.exp(coef["ln_a"]) * p["n_particles"] ** coef["b_particles"]
                       * p["estimated_steps"] ** coef["b_steps"])
        return np.array(out)

    done = pd.DataFrame([{"case_id": c.case_id, **{n: c.point[n] for n in NAMES}, "status": "ok"} for c in lds[:48]])
    scatter = np.exp(0.2 * np.random.default_rng(3).standard_normal(48))
    done["cpu_time"] = 1.7 * law(lds[:48]) * scatter
    to_go = cpu_hours_to_go(cfg, {"lds": done, "lattice": done.iloc[:0]})
    factor = 1.7 * np.exp(np.median(np.log(scatter)))  # the calibration: the median log ratio of measured to planned
    assert to_go["lds"] == pytest.approx(factor * law(lds[48:]).sum() / 3600, rel=1e-9)
    lattice = [c for c in cases if c.sweep == "lattice"]
    assert to_go["lattice"] == pytest.approx(factor * law(lattice).sum() / 3600, rel=1e-9)
    fresh = cpu_hours_to_go(cfg, {"lds": done.iloc[:0], "lattice": done.iloc[:0]})
    assert fresh["lds"] == pytest.approx(law(lds).sum() / 3600, rel=1e-9)
    table = progress(planned_sweeps(cfg), {"lds": done, "lattice": done.iloc[:0]}, to_go)
    assert list(table["cpu_hours_to_go"]) == [round(to_go["lds"], 1), round(to_go["lattice"], 1)]


@pytest.fixture(scope="module")
def published():
    assert (DOCS / "config.yaml").exists(), "docs/study is published (tools/publish_study.py)"
    cfg = spreadmap_config.load(DOCS / "config.yaml")
    return cfg, planned_sweeps(cfg)


def test_published_cases_are_planned_cases_as_simulated(published):
    cfg, plan = published
    for name, cases in plan.items():
        table = pd.read_csv(DOCS / f"cases_{name}.csv")
        labels = {readable_part(cid): label for cid, label in cases} if name == "lds" else None
        planned = {readable_part(cid) for cid, _ in cases}
        assert set(table["case_id"]) <= planned, name
        assert list(table["index"]) == sorted(table["index"]), name
        if labels:
            assert all(labels[c] == {"sweep": "lds", "index": i} for c, i in zip(table["case_id"], table["index"]))
        # the design point each case simulated is the planned point (to the case id's rounding);
        # the published ids are from before content keys (issue 35): their readable part alone
        ids = [readable_id(r, r["preset"], r["seed"]) for r in table.to_dict("records")]
        assert ids == list(table["case_id"]), name
        assert set(table["status"]) <= {"ok", "failed"}


def test_published_progress_recomputes(published):
    cfg, plan = published
    tables = {name: pd.read_csv(DOCS / f"cases_{name}.csv") for name in plan}
    computed = progress(plan, tables)
    stored = pd.read_csv(DOCS / "progress.csv")
    assert list(stored["sweep"]) == list(computed["sweep"])
    for column in ("planned", "finished", "ok", "failed"):
        assert list(stored[column]) == list(computed[column]), column
    np.testing.assert_allclose(stored["cpu_hours"], computed["cpu_hours"], atol=1e-3)
    if "cpu_hours_to_go" in stored:
        to_go = cpu_hours_to_go(cfg, tables)
        np.testing.assert_allclose(stored["cpu_hours_to_go"], [round(to_go[s], 1) for s in stored["sweep"]], atol=0.051)


def test_the_loops_cases_so_far_follow_its_steps(config):
    """Start 4 LDS cases, batches of 2 (one LDS, one active): the loop's cases are the first four
    of the sequence, then each step's batch in order, labelled by batch and LDS share as the
    workflow's converge table labels them."""
    from spreadlab.study.cases import loop_cases

    cfg = copy.deepcopy(config)
    cfg["sweeps"] = {"lds": {"seed": 42, "partitions": [4]}}
    cfg["converge"] = {"start": 4, "batch": 2}
    lds = [c for c in planned_cases(cfg, lds_points=6) if c.sweep == "lds"]
    extra = {"f": 0.2, "d_um": 20.0, "h_um": 60.0, "v_mm_s": 7.0}
    steps = [{"n": 6, "next_batch": [], "is_lds": [True] * 4 + [True, False] + [True, False]},
             {"n": 4, "next_batch": [lds[4].point, extra]}]
    steps[0]["next_batch"] = [lds[5].point, extra]
    got = loop_cases(cfg, steps)
    preset = cfg["preset"]
    assert [cid for cid, _ in got] == [c.case_id for c in lds[:5]] + [case_id(extra, preset, cfg), lds[5].case_id,
                                                                     case_id(extra, preset, cfg)]
    assert [lab["batch"] for _, lab in got] == [0, 0, 0, 0, 1, 1, 2, 2]
    assert [lab["lds"] for _, lab in got] == [True] * 5 + [False, True, False]


def test_published_loop_cases_are_its_steps_cases(published):
    """cases_converge.csv (the loop so far) holds the cases its published steps planned, in run order,
    with their batch and LDS-share labels: the cases of the last step, whose CPU it equals, then
    those of the batch that step chose which had finished when it was published."""
    from spreadlab.study.cases import loop_cases

    cfg, _ = published
    steps = [json.loads(s.read_text()) for s in (DOCS / "converge" / "steps").glob("step_*.json")]
    table = pd.read_csv(DOCS / "cases_converge.csv")
    planned = {readable_part(cid): label for cid, label in loop_cases(cfg, steps)}  # published before content keys
    assert list(table["index"]) == sorted(table["index"])
    for row in table.to_dict("records"):
        label = planned[row["case_id"]]
        assert (row["index"], row["batch"], bool(row["lds"])) == (label["index"], label["batch"], label["lds"])
    last = max(steps, key=lambda s: s["n"])
    assert last["n"] <= len(table) <= (last.get("next_n") or last["n"])  # a stopped loop has no next batch
    stepped = table.iloc[:last["n"]]
    assert stepped["cpu_time"].sum() / 3600 == pytest.approx(last["cpu_hours"], rel=1e-6)
    after = loop_cases(cfg, steps)[last["n"]:]
    assert set(table["case_id"].iloc[last["n"]:]) <= {readable_part(cid) for cid, _ in after}


def test_published_partitions_recompute_from_the_cases_with_numpy_and_scipy(published):
    """convergence/partitions.csv (the workflow's study rule) against the five statistics computed
    here with numpy and scipy from the published cases: the LDS's first N usable cases in plan
    order for each partition, each lattice by k; and the verdicts of summary.json follow from
    the changes (none below the tolerance, so neither sweep converged)."""
    from scipy import stats

    cfg, _ = published
    parts = pd.read_csv(DOCS / "convergence" / "partitions.csv")
    summary = json.loads((DOCS / "convergence" / "summary.json").read_text())
    tables = {"lds": pd.read_csv(DOCS / "cases_lds.csv"), "lattice": pd.read_csv(DOCS / "cases_lattice.csv")}
    for row in parts.to_dict("records"):
        table = tables[row["sweep"]]
        if row["sweep"] == "lds":
            sample = table[table["index"] < row["partition"]]
        else:
            sample = table[table["k"] ** len(NAMES) == row["partition"]]  # a lattice's partition is its size k^4
        sample = sample[usable(sample)]
        assert len(sample) == row["n_usable"], row
        for target in ("mfr", "pd"):
            x = sample[target].to_numpy(float)
            expected = {"mean": x.mean(), "std": x.std(ddof=1), "median": np.median(x),
                        "kurtosis": stats.kurtosis(x, fisher=True, bias=True), "skewness": stats.skew(x, bias=True)}
            for name, value in expected.items():
                assert row[f"{target}_{name}"] == pytest.approx(value, rel=1e-9, abs=1e-12), (row["sweep"], target, name)
    tol = cfg["study_rule"]["tolerance"]
    for sweep in ("lds", "lattice"):
        changes = parts.loc[parts["sweep"] == sweep, "max_change"].dropna()
        assert (changes > tol).all() and summary["sweeps"][sweep]["converged_n"] is None, sweep
    assert list(parts.loc[parts["sweep"] == "lds", "partition"]) == sorted(cfg["sweeps"]["lds"]["partitions"])
    assert list(parts.loc[parts["sweep"] == "lattice", "partition"]) == sorted(k ** len(NAMES)
                                                                               for k in cfg["sweeps"]["lattice"]["k"])


def test_published_summary_recomputes_from_the_published_files(published):
    """summary.md and the trend tables are what spreadlab.study.summary makes of docs/study's
    committed cases, steps, surrogate and maps today."""
    from spreadlab.study.summary import summary_markdown, trends

    cfg, _ = published
    effects = trends(DOCS, cfg.get("ranges"))
    assert summary_markdown(DOCS, effects) == (DOCS / "summary.md").read_text()
    assert sorted(f"trend_{v}.csv" for v in effects) == sorted(p.name for p in DOCS.glob("trend_*.csv"))
    for variable, effect in effects.items():
        pd.testing.assert_frame_equal(effect, pd.read_csv(DOCS / f"trend_{variable}.csv"), rtol=1e-9)


@pytest.mark.parametrize("check, cases", [("heldout", "cases_heldout.csv"), ("heldout2", "cases_heldout2.csv")])
def test_published_heldout_scores_recompute_from_the_cases_and_the_predictions(check, cases):
    """Each held-out check's score.csv and score.json against the committed runs and the predictions
    committed before them, recomputed here: seed means of the usable runs matched to the points by
    design point, the SD of a seed mean sqrt(model^2 + (run^2 - model^2) / n), |z| <= 1.96 inside,
    the coverage interval from scipy's exact binomial test."""
    from scipy import stats

    folder = DOCS / check
    points = pd.read_csv(folder / "points.csv").drop_duplicates("name")
    predictions = pd.read_csv(folder / "predictions.csv").set_index("name")
    runs = pd.read_csv(DOCS / cases)
    runs = runs[usable(runs)]
    key = list(NAMES)
    runs = runs.drop(columns=["name"], errors="ignore").merge(points[["name", *key]], on=key, how="inner")
    assert runs["name"].nunique() == len(points) == 12
    score = pd.read_csv(folder / "score.csv")
    summary = {r["target"]: r for r in json.loads((folder / "score.json").read_text())}
    assert {"mfr", "pd"} <= set(summary)
    for target, stated in summary.items():
        g = runs.groupby("name")[target]
        mean, n = g.mean(), g.size()
        model_sd, run_sd = predictions[f"{target}_model_sd"], predictions[f"{target}_run_sd"]
        sd = np.sqrt(model_sd ** 2 + np.clip(run_sd ** 2 - model_sd ** 2, 0, None) / n)
        z = ((mean - predictions[target]) / sd).dropna()
        inside = int((z.abs() <= 1.959964).sum())
        assert stated["inside"] == inside and stated["points"] == len(z) == 12, (check, target)
        ci = stats.binomtest(inside, len(z)).proportion_ci(confidence_level=0.95, method="exact")
        assert stated["coverage_low"] == pytest.approx(ci.low) and stated["mean_z2"] == pytest.approx(np.mean(z ** 2))
        rows = score[score["target"] == target].set_index("name")
        np.testing.assert_allclose(rows.loc[z.index, "z"], z, rtol=1e-9)


def test_publishing_names_cases_by_the_workflow_directorys_own_template(tmp_path):
    """tools/publish_study.py keys the planned cases with the scene template of the workflow directory
    it publishes (which may be another version than this repository's): a case finished there is
    published, and one at the same design point under another content id (this repository's
    template, say) is not, and is named on stderr."""
    import subprocess
    import sys

    from spreadmap.case.render import template_sha256

    wf = make_workflow(tmp_path, {"sweeps": {"lds": {"seed": 42, "partitions": [3]}}})
    template = wf / "yade_scripts" / "spreading_case.py"
    template.write_text(template.read_text() + "ANOTHER_VERSION_OF_THE_SCENE = 1\n")  # code: a comment keys nothing
    cfg = spreadmap_config.load(wf / "config.yaml")
    theirs = planned_sweeps(cfg, scene_sha256=template_sha256(template))["lds"]
    ours = planned_sweeps(cfg)["lds"]
    assert [readable_part(c) for c, _ in theirs] == [readable_part(c) for c, _ in ours]
    assert not {c for c, _ in theirs} & {c for c, _ in ours}
    points = {readable_part(c.case_id): {n: c.point[n] for n in NAMES} for c in planned_cases(cfg)}
    for cid in (theirs[0][0], ours[1][0]):  # finished: the first under their template, the second under ours
        case = wf / "results" / "cases" / cid
        case.mkdir(parents=True)
        (case / "metrics.json").write_text(json.dumps(_metrics(cid, points[readable_part(cid)], cfg["preset"], 1)))
        (case / "benchmark.tsv").write_text("s\th:m:s\tmax_rss\n10\t0:00:10\t200\n")
    run = subprocess.run([sys.executable, str(ROOT / "tools" / "publish_study.py"), str(wf), "--out", str(tmp_path / "out")],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    published = pd.read_csv(tmp_path / "out" / "cases_lds.csv")
    assert list(published["case_id"]) == [theirs[0][0]]
    assert f"1 case folders of {wf} are at planned design points but under other content ids" in run.stderr
    assert ours[1][0] in run.stderr
