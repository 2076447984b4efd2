"""Resuming a published study on a new machine (spreadmap/restore.py, tools/restore_study.py): the
restored cases give back the published table exactly, a real result is never overwritten, and
Snakemake plans no YADE run for a restored case. The dry run is cheap (no YADE)."""
import json
import os
import subprocess
import sys

import pandas as pd
import yaml
from conftest import ROOT, make_workflow, planned_jobs, snakemake

from spreadmap.checksums import write_manifest
from spreadmap.restore import restore_cases, restore_steps
from spreadmap.table import build_table

STUDY = ROOT / "docs" / "study"


def _restored_table(workdir, published):
    """The results table the workflow's own table builder makes from the restored files, with the
    published labels (sweep, index, batch, lds)."""
    labels = [{k: row[k] for k in ("sweep", "index", "batch", "lds") if k in row}
              for row in published.to_dict("records")]
    folders = [workdir / "results" / "cases" / cid for cid in published["case_id"]]
    return build_table([f / "metrics.json" for f in folders], [f / "benchmark.tsv" for f in folders], labels)


def test_the_restored_cases_give_back_the_published_table(tmp_path):
    """Every published case of the main job's loop (242 rows: ok, flagged and re-read ones, with
    empty cells) restored and put through the workflow's table builder is the published table,
    column for column, once both are read as CSV."""
    published = pd.read_csv(STUDY / "cases_converge.csv")
    counts = restore_cases([STUDY / "cases_converge.csv"], tmp_path, mtime=1.0e9)
    assert counts == {"restored": len(published), "kept_real": 0, "duplicates": 0, "not_finished": 0, "already": 0}
    rebuilt_csv = tmp_path / "rebuilt.csv"
    _restored_table(tmp_path, published).to_csv(rebuilt_csv, index=False)
    rebuilt = pd.read_csv(rebuilt_csv)
    assert list(rebuilt.columns) == list(published.columns)
    pd.testing.assert_frame_equal(rebuilt, published, check_exact=True)
    assert published["flagged"].dtype == bool and published["reason"].isna().all()  # the empty cells went through
    record = json.loads((tmp_path / "results/cases" / published["case_id"][3] / "restored.json").read_text())
    assert record["row"] == 3 and record["restored_from"].endswith("cases_converge.csv")
    assert os.path.getmtime(tmp_path / "results/cases" / published["case_id"][3] / "metrics.json") == 1.0e9
    # run again (a table grew): the cases restored before keep their files and times
    again = restore_cases([STUDY / "cases_converge.csv"], tmp_path, mtime=2.0e9)
    assert again["already"] == len(published) and again["restored"] == 0
    assert os.path.getmtime(tmp_path / "results/cases" / published["case_id"][3] / "metrics.json") == 1.0e9


def test_a_case_with_a_raw_record_is_left_alone(tmp_path):
    published = pd.read_csv(STUDY / "cases_lds.csv")
    real = tmp_path / "results" / "cases" / published["case_id"][0]
    real.mkdir(parents=True)
    (real / "raw.json").write_text("{}")
    (real / "metrics.json").write_text('{"mfr": 0.5}')
    counts = restore_cases([STUDY / "cases_lds.csv", STUDY / "cases_converge.csv"], tmp_path, mtime=1.0e9)
    assert counts["kept_real"] == 1 and counts["restored"] == len(set(pd.concat(
        [published, pd.read_csv(STUDY / "cases_converge.csv")])["case_id"])) - 1
    assert (real / "metrics.json").read_text() == '{"mfr": 0.5}' and not (real / "restored.json").exists()
    # the LDS cases the loop shares with the sweep were restored once (from the first table)
    assert counts["duplicates"] == len(set(published["case_id"]) & set(pd.read_csv(STUDY / "cases_converge.csv")["case_id"]))


def test_steps_are_restored_newer_than_the_cases_in_the_order_they_were_made(tmp_path):
    steps = sorted((STUDY / "converge" / "steps").glob("step_*.json"))
    names = restore_steps(steps, tmp_path, mtime=1.0e9)
    assert names[:3] == ["step_32.json", "step_48.json", "step_64.json"]  # by number, not by name
    times = [os.path.getmtime(tmp_path / "results" / "converge" / n) for n in names]
    assert times[0] > 1.0e9 and all(b > a for a, b in zip(times, times[1:]))
    assert restore_steps(steps, tmp_path, mtime=2.0e9) == []  # an existing step is left alone


def test_snakemake_plans_no_run_for_a_restored_case(tmp_path):
    """The study's LDS sweep at N = 16 (the published config's sequence): on a new machine all 16
    cases would run; restored from docs/study, none does and the table is rebuilt from them (the
    tool, as the README's resuming section calls it)."""
    study_cfg = yaml.safe_load((STUDY / "config.yaml").read_text())
    wf = make_workflow(tmp_path, {"sweeps": {"lds": {**study_cfg["sweeps"]["lds"], "partitions": [16]}},
                                  "ranges": study_cfg["ranges"], "preset": study_cfg["preset"]})
    before = snakemake(wf, "-n", "results/tables/lds.csv")
    assert before.returncode == 0, before.stderr[-3000:]
    assert planned_jobs(before.stdout)["run_case"] == 16
    tool = subprocess.run([sys.executable, str(ROOT / "tools" / "restore_study.py"), str(wf)],
                          capture_output=True, text=True, timeout=120)
    assert tool.returncode == 0, tool.stderr
    assert "loop steps" in tool.stdout
    # the held-out check's predictions, made before its runs, come back for scoring
    assert (wf / "heldout" / "predictions.csv").read_text() == (STUDY / "heldout" / "predictions.csv").read_text()
    after = snakemake(wf, "-n", "results/tables/lds.csv")
    assert after.returncode == 0, after.stderr[-3000:]
    jobs = planned_jobs(after.stdout)
    assert "run_case" not in jobs and "render_case" not in jobs and jobs["results_table"] == 1, after.stdout[-2000:]


def test_a_case_that_did_not_finish_is_not_restored(tmp_path):
    """A failed case of a published table gets a new try on the new machine (no metrics.json is
    written for it, so the workflow runs it); the finished ones beside it are restored."""
    published = pd.read_csv(STUDY / "cases_lds.csv").head(3)
    published.loc[1, "status"] = "failed"
    published["reason"] = published["reason"].astype(object)
    published.loc[1, "reason"] = "yade exited with code 137 (killed)"
    table = tmp_path / "cases_x.csv"
    published.to_csv(table, index=False)
    write_manifest(tmp_path)  # published: its checksum beside it
    counts = restore_cases([table], tmp_path, mtime=1.0e9)
    assert counts["restored"] == 2 and counts["not_finished"] == 1
    assert not (tmp_path / "results" / "cases" / published["case_id"][1]).exists()
    assert (tmp_path / "results" / "cases" / published["case_id"][2] / "metrics.json").exists()
