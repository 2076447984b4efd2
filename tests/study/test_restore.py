"""Resuming a published study on a new machine (spreadlab/study/restore.py, tools/restore_study.py): the
restored cases give back the published table exactly, a real result is never overwritten, and
Snakemake plans no YADE run for a restored case of its own scene and every run for one of another
scene; a table published before content keys (issue 35) is refused. The dry runs are cheap (no YADE).

The tables of docs/study were published before content keys: the tests restore copies of them keyed
for the published config and the current template (conftest.keyed_table), as a table published
after content keys would be."""
import json
import os
import re
import shutil
import subprocess
import sys

import pandas as pd
import pytest
import yaml
from conftest import ROOT, keyed_table, make_workflow, planned_jobs, snakemake, study_config

from spreadlab.study.checksums import write_manifest
from spreadlab.study.restore import UnkeyedTableError, restore_cases, restore_steps, restore_time
from spreadmap import config as spreadmap_config
from spreadmap.case.identity import readable_part
from spreadmap.records import current_columns
from spreadmap.table import build_table

STUDY = ROOT / "docs" / "study"


def published_keyed(folder, names, config=None, rows=None):
    """A published folder holding the study's tables `names` keyed for `config` (default: the
    study's), their first `rows` rows, with its SHA256SUMS. Returns {name: path}."""
    config = study_config() if config is None else config
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    for name in names:
        table = pd.read_csv(STUDY / name)
        keyed_table(table if rows is None else table.head(rows), config).to_csv(folder / name, index=False)
        out[name] = folder / name
    write_manifest(folder)
    return out


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
    table = published_keyed(tmp_path / "published", ["cases_converge.csv"])["cases_converge.csv"]
    published = current_columns(pd.read_csv(table))  # the builder names the layer fill as it is called now
    counts = restore_cases([table], tmp_path, mtime=1.0e9)
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
    again = restore_cases([table], tmp_path, mtime=2.0e9)
    assert again["already"] == len(published) and again["restored"] == 0
    assert os.path.getmtime(tmp_path / "results/cases" / published["case_id"][3] / "metrics.json") == 1.0e9


def test_a_case_with_a_raw_record_is_left_alone(tmp_path):
    tables = published_keyed(tmp_path / "published", ["cases_lds.csv", "cases_converge.csv"])
    published, converge = pd.read_csv(tables["cases_lds.csv"]), pd.read_csv(tables["cases_converge.csv"])
    real = tmp_path / "results" / "cases" / published["case_id"][0]
    real.mkdir(parents=True)
    (real / "raw.json").write_text("{}")
    (real / "metrics.json").write_text('{"mfr": 0.5}')
    counts = restore_cases(list(tables.values()), tmp_path, mtime=1.0e9)
    assert counts["kept_real"] == 1 and counts["restored"] == len(set(pd.concat([published, converge])["case_id"])) - 1
    assert (real / "metrics.json").read_text() == '{"mfr": 0.5}' and not (real / "restored.json").exists()
    # the LDS cases the loop shares with the sweep were restored once (from the first table)
    assert counts["duplicates"] == len(set(published["case_id"]) & set(converge["case_id"]))


def test_steps_are_restored_newer_than_the_cases_in_the_order_they_were_made(tmp_path):
    steps = sorted((STUDY / "converge" / "steps").glob("step_*.json"))
    names = restore_steps(steps, tmp_path, mtime=1.0e9)
    assert names[:3] == ["step_32.json", "step_48.json", "step_64.json"]  # by number, not by name
    times = [os.path.getmtime(tmp_path / "results" / "converge" / n) for n in names]
    assert times[0] > 1.0e9 and all(b > a for a, b in zip(times, times[1:]))
    assert restore_steps(steps, tmp_path, mtime=2.0e9) == []  # an existing step is left alone


def _lds16(tmp_path, **overrides):
    """A workflow of the study's LDS sweep at N = 16 (the published config's sequence)."""
    study_cfg = yaml.safe_load((STUDY / "config.yaml").read_text())
    return make_workflow(tmp_path, {"sweeps": {"lds": {**study_cfg["sweeps"]["lds"], "partitions": [16]}},
                                    "ranges": study_cfg["ranges"], "preset": study_cfg["preset"], **overrides})


def _published_for(wf, folder):
    """A published study folder whose LDS table is keyed for the workflow wf's config (as if run
    there), with the study's steps and held-out files."""
    published_keyed(folder, ["cases_lds.csv"], config=spreadmap_config.load(wf / "config.yaml"), rows=16)
    for sub in ("converge/steps", "heldout"):
        shutil.copytree(STUDY / sub, folder / sub)
    write_manifest(folder)
    return folder


def _restore_tool(wf, published):
    return subprocess.run([sys.executable, str(ROOT / "tools" / "restore_study.py"), str(wf), "--published", str(published)],
                          capture_output=True, text=True, timeout=120)


def test_snakemake_plans_no_run_for_a_restored_case(tmp_path):
    """The study's LDS sweep at N = 16: on a new machine all 16 cases would run; restored from a
    table published under the same config and template, none does and the table is rebuilt from
    them (the tool, as the README's resuming section calls it)."""
    wf = _lds16(tmp_path)
    for path in [wf / "Snakefile", *(wf / "rules").rglob("*"), *(wf / "scripts").rglob("*")]:
        os.utime(path)  # dated now, as a fresh git clone dates them: the restored files must be newer
    before = snakemake(wf, "-n", "results/tables/lds.csv")
    assert before.returncode == 0, before.stderr[-3000:]
    assert planned_jobs(before.stdout)["run_case"] == 16
    tool = _restore_tool(wf, _published_for(wf, tmp_path / "published"))
    assert tool.returncode == 0, tool.stderr
    assert "16 cases restored" in tool.stdout and "loop steps" in tool.stdout
    # the held-out check's predictions, made before its runs, come back for scoring
    assert (wf / "heldout" / "predictions.csv").read_text() == (STUDY / "heldout" / "predictions.csv").read_text()
    after = snakemake(wf, "-n", "results/tables/lds.csv")
    assert after.returncode == 0, after.stderr[-3000:]
    jobs = planned_jobs(after.stdout)
    assert "run_case" not in jobs and "render_case" not in jobs and jobs["results_table"] == 1, after.stdout[-2000:]
    # nor a restored case's metrics (Snakemake re-runs a job whose outputs are older than its script)
    assert "case_metrics" not in jobs, after.stdout[-2000:]


def test_restored_files_are_dated_after_the_workflow_code(tmp_path):
    """An hour back, but never older than the Snakefile, rules/ or scripts/ (spreadlab.study.restore's
    restore_time): a fresh clone dates its code at the clone."""
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "x.py").write_text("")
    os.utime(tmp_path / "scripts" / "x.py", (5000.0, 5000.0))
    assert restore_time(tmp_path, now=10000.0) == 6400.0  # an hour back: newer than the code
    os.utime(tmp_path / "scripts" / "x.py", (9000.0, 9000.0))
    assert restore_time(tmp_path, now=10000.0) == 9001.0  # just after the code
    os.utime(tmp_path / "scripts" / "x.py", (20000.0, 20000.0))
    assert restore_time(tmp_path, now=10000.0) == 10000.0  # never in the future


def test_a_case_published_for_another_scene_is_never_taken_for_this_one(tmp_path):
    """Cases published under another material (density 4430 kg/m3, titanium's) go back under their
    own ids, beside this scene's: the workflow of the shipped material still plans all 16 runs, and
    switching its material to the published one plans none."""
    wf = _lds16(tmp_path)
    other = spreadmap_config.load(wf / "config.yaml")
    other["material"]["density_kg_m3"] = 4430.0
    tables = published_keyed(tmp_path / "published", ["cases_lds.csv"], config=other, rows=16)
    counts = restore_cases(list(tables.values()), wf, mtime=1.0e9)
    assert counts["restored"] == 16
    dry = snakemake(wf, "-n", "results/tables/lds.csv")
    assert dry.returncode == 0, dry.stderr[-3000:]
    assert planned_jobs(dry.stdout)["run_case"] == 16  # none of the restored cases is of this scene
    planned = set(re.findall(r"results/cases/([^/\s]+)/raw\.json", dry.stdout))
    restored = set(pd.read_csv(tables["cases_lds.csv"])["case_id"])
    assert len(planned) == 16 and not planned & restored
    assert {readable_part(c) for c in planned} == {readable_part(c) for c in restored}  # the same points
    config = yaml.safe_load((wf / "config.yaml").read_text())
    config["material"]["density_kg_m3"] = 4430.0
    (wf / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    switched = snakemake(wf, "-n", "results/tables/lds.csv")
    assert switched.returncode == 0, switched.stderr[-3000:]
    assert "run_case" not in planned_jobs(switched.stdout), switched.stdout[-2000:]


def test_a_table_published_before_content_keys_is_refused(tmp_path):
    """docs/study's tables name cases without a content key: the scene they were run with is not
    recorded, so the tool refuses them, naming the table and what to do, and restores nothing."""
    with pytest.raises(UnkeyedTableError, match=r"cases_lds.csv: 256 of its 256 cases have ids without a content key"):
        restore_cases([STUDY / "cases_lds.csv"], tmp_path, mtime=1.0e9)
    assert not (tmp_path / "results").exists()
    wf = _lds16(tmp_path)
    tool = _restore_tool(wf, STUDY)
    assert tool.returncode == 2 and tool.stderr.count("\n") == 1, tool.stderr
    assert "restore_study: refused:" in tool.stderr and "publish the table again" in tool.stderr
    assert not (wf / "results").exists() and not (wf / "heldout").exists()


def test_a_row_whose_id_names_another_point_is_refused(tmp_path):
    """A row's id must name its own preset, design point and seed: one that names another case's
    (an id copied onto another row) is refused before anything is restored."""
    table = keyed_table(pd.read_csv(STUDY / "cases_lds.csv").head(3), study_config())
    table.loc[1, "case_id"] = table.loc[0, "case_id"]
    table.to_csv(tmp_path / "cases_x.csv", index=False)
    write_manifest(tmp_path)
    with pytest.raises(UnkeyedTableError, match=r"row 1: case id .* does not name the row's own"):
        restore_cases([tmp_path / "cases_x.csv"], tmp_path / "work", mtime=1.0e9)
    assert not (tmp_path / "work").exists()


def test_a_case_that_did_not_finish_is_not_restored(tmp_path):
    """A failed case of a published table gets a new try on the new machine (no metrics.json is
    written for it, so the workflow runs it); the finished ones beside it are restored."""
    published = keyed_table(pd.read_csv(STUDY / "cases_lds.csv").head(3), study_config())
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
