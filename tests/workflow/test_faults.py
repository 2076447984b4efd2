"""Faults a long study meets that need no DEM run (issue 35), each with what must hold after it:

- a points CSV with duplicate names, names that are paths, missing or non-numeric values: refused
  before anything is planned, naming the row (its line in the file) and the column;
- a published cases table that changed since it was published: the restore refuses it (naming
  the file and how to re-publish) before it restores any case; an intact one goes through;
- a truncated raw.json or metrics.json, a corrupted saved model, a half-written table: detected
  and never read as data; under Snakemake the file is moved aside and the next run re-makes it;
- a full disk (a file-size limit) while a table is written: the previous table survives byte for
  byte, no temporary file is left, and the error names the file and the limit.

No YADE: the Snakemake tests only plan or run analysis rules (a few seconds each).
"""
from __future__ import annotations

import errno
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
import time
import warnings

import pandas as pd
import pytest
from conftest import ROOT, keyed_table, make_workflow, planned_jobs, snakemake, study_config

from spreadlab.study.checksums import PublishedFileError, check_folder, republish_if_listed, verified_bytes, write_manifest
from spreadlab.study.restore import case_record, restore_cases, restore_steps
from spreadmap.case.launcher import finished_simulation
from spreadmap.records import CorruptFileError, current_columns, read_metrics, read_raw, read_table
from spreadmap.sampling import chosen_points
from spreadmap.table import build_table

pytestmark = pytest.mark.faults
PYTHON = sys.executable
STUDY = ROOT / "docs" / "study"
HEADER = "name,preset,seed,f,d_um,h_um,v_mm_s\n"
GOOD = "a,default,1,0.3,30,65,10\n"


# ------------------------------------------------------------------------------------------------
# points CSV
# ------------------------------------------------------------------------------------------------
def points(tmp_path, text, named=None, presets=("default", "smoke")):
    (tmp_path / "pts.csv").write_text(text)
    return chosen_points({"csv": "pts.csv", "named": named or {}}, tmp_path, presets=presets)


@pytest.mark.parametrize("rows, row, column, why", [
    # duplicate names: the same name and seed twice, or one name for two points or presets
    (GOOD + GOOD, 3, "name", "duplicate: 'a' with seed 1 is row 2 already"),
    (GOOD + "a,default,2,0.3,30,65,10\n" + "a,default,2,0.3,30,65,10\n", 4, "name", "is row 3 already"),
    (GOOD + "a,default,2,0.3,30,70,10\n", 3, "name", "names another point or preset on row 2"),
    (GOOD + "a,smoke,2,0.3,30,65,10\n", 3, "name", "names another point or preset on row 2"),
    # names that are paths
    ("../up,default,1,0.3,30,65,10\n", 2, "name", "is a path"),
    ("sub/dir,default,1,0.3,30,65,10\n", 2, "name", "is a path"),
    ("..,default,1,0.3,30,65,10\n", 2, "name", "is a path"),
    ("c:\\x,default,1,0.3,30,65,10\n", 2, "name", "is a path"),
    (",default,1,0.3,30,65,10\n", 2, "name", "an empty name"),
    ("  ,default,1,0.3,30,65,10\n", 2, "name", "an empty name"),
    # missing values: an empty cell, a short row
    (GOOD + "b,default,1,0.3,,65,10\n", 3, "d_um", "missing value"),
    (GOOD + "b,default,1,0.3,30,65\n", 3, "v_mm_s", "missing value (the row has 6 fields, the header 7)"),
    # non-numeric, non-finite, non-positive
    (GOOD + "b,default,1,abc,30,65,10\n", 3, "f", "'abc' is not a number"),
    (GOOD + "b,default,1,0.3,30um,65,10\n", 3, "d_um", "'30um' is not a number"),
    (GOOD + "b,default,1,0.3,30,nan,10\n", 3, "h_um", "'nan' is not a positive number"),
    (GOOD + "b,default,1,0.3,30,65,inf\n", 3, "v_mm_s", "'inf' is not a positive number"),
    (GOOD + "b,default,1,0.3,-30,65,10\n", 3, "d_um", "'-30' is not a positive number"),
    (GOOD + "b,default,x,0.3,30,65,10\n", 3, "seed", "seed = 'x' is not allowed"),
    # a preset that is not one, or that would make a case id a path
    (GOOD + "b,nosuch,1,0.3,30,65,10\n", 3, "preset", "'nosuch' is not a preset (the config's presets: default, smoke)"),
    (GOOD + "b,../x,1,0.3,30,65,10\n", 3, "preset", "'../x' is not a preset"),
])
def test_a_bad_points_csv_is_refused_naming_row_and_column(tmp_path, rows, row, column, why):
    with pytest.raises(ValueError) as error:
        points(tmp_path, HEADER + rows)
    message = str(error.value)
    assert f"pts.csv, row {row}, column '{column}': " in message and why in message, message


def test_the_points_csv_row_is_the_files_line_blank_lines_and_quoted_line_breaks_counted(tmp_path):
    text = ("note," + HEADER + "," + GOOD + "\n\n" + '"two\nlines",b,default,1,0.3,30,65,10\n'
            + ",c,default,1,0.3,30,65,x\n")
    with pytest.raises(ValueError, match=r"row 7, column 'v_mm_s': 'x' is not a number"):
        points(tmp_path, text)
    with pytest.raises(ValueError, match=r"row 5, column 'name': name 'b\\nc' has a control character"):
        points(tmp_path, HEADER + GOOD + "\n\n" + '"b\nc",default,1,0.3,30,65,10\n')
    with pytest.raises(ValueError, match=r"row 2, column 8 \(no name in the header\): the row has 8 fields"):
        points(tmp_path, HEADER + "a,default,1,0.3,30,65,10,extra\n")
    with pytest.raises(ValueError, match=r"row 1, column 'f': given twice \(columns 4 and 8\)"):
        points(tmp_path, HEADER.strip() + ",f\n" + GOOD.strip() + ",0.3\n")


def test_a_points_csv_name_that_is_also_a_named_point_is_refused(tmp_path):
    named = {"a": {"f": 0.3, "d_um": 30, "h_um": 65, "v_mm_s": 10}}
    with pytest.raises(ValueError, match=r"row 2, column 'name': 'a' is also the name of a point in the config"):
        points(tmp_path, HEADER + GOOD, named=named)
    with pytest.raises(ValueError, match=r"config key 'points.named': name 'x/y' is a path"):
        chosen_points({"named": {"x/y": named["a"]}}, tmp_path)


def test_good_points_csvs_read_as_before(tmp_path):
    """A name repeats as the same point's other packing seeds (the held-out check's files);
    without a name column rows are named after the file; blank lines and spaces are allowed."""
    held = chosen_points({"csv": "docs/study/heldout/points.csv"}, ROOT, presets={"default": {}})
    assert len(held) == 48 and [p["seed"] for p in held[:4]] == [1, 2, 3, 4]
    assert held[0] == {"name": "heldout_01", "point": {"f": 0.3698, "d_um": 21.293, "h_um": 57.542, "v_mm_s": 10.921},
                       "preset": "default", "seed": 1}
    got = points(tmp_path, "f, d_um, h_um, v_mm_s, seed\n0.3, 30, 65, 10, \n\n0.2,40,60,5,3\n")
    assert got == [{"name": "pts_0", "point": {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}, "preset": None,
                    "seed": None},
                   {"name": "pts_1", "point": {"f": 0.2, "d_um": 40.0, "h_um": 60.0, "v_mm_s": 5.0}, "preset": None,
                    "seed": 3}]


def test_the_workflow_refuses_a_bad_points_csv_before_planning(tmp_path):
    wf = make_workflow(tmp_path, {"points": {"named": {}, "csv": "pts.csv"}, "pictures": {"cases": [], "vtk": []}},
                       ("points", "pictures"))
    (wf / "pts.csv").write_text(HEADER + GOOD + "b,default,1,0.3,30,sixty,10\n")
    dry = snakemake(wf, "-n")
    out = dry.stdout + dry.stderr
    assert dry.returncode != 0
    assert "bad chosen points: points CSV" in out and "row 3, column 'h_um': 'sixty' is not a number" in out, out
    assert "Traceback" not in out, out[-3000:]


# ------------------------------------------------------------------------------------------------
# published tables and their checksums
# ------------------------------------------------------------------------------------------------
@pytest.fixture
def published(tmp_path):
    """A small published study folder: 5 cases of the LDS table and two loop steps, with SHA256SUMS."""
    folder = tmp_path / "published"
    (folder / "converge" / "steps").mkdir(parents=True)
    table = keyed_table(pd.read_csv(STUDY / "cases_lds.csv").head(5), study_config())
    table.to_csv(folder / "cases_lds.csv", index=False)
    for name in ("step_32.json", "step_48.json"):
        shutil.copyfile(STUDY / "converge" / "steps" / name, folder / "converge" / "steps" / name)
    write_manifest(folder)
    return folder


def test_the_repositorys_published_folders_match_their_checksums():
    """What restore_study.py would restore is what was published (run after a publish:
    tools/publish_checksums.py; this checks with --check)."""
    run = subprocess.run([PYTHON, str(ROOT / "tools" / "publish_checksums.py"), "--check"], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    manifest = (STUDY / "SHA256SUMS").read_text()
    for name in ("cases_lds.csv", "cases_converge.csv", "converge/steps/step_32.json", "heldout/predictions.csv"):
        assert re.search(rf"^[0-9a-f]{{64}}  {re.escape(name)}$", manifest, re.M), name
    assert "cases.csv" in (ROOT / "docs" / "precision" / "SHA256SUMS").read_text()


def test_an_intact_published_table_is_restored(published, tmp_path):
    work = tmp_path / "work"
    counts = restore_cases([published / "cases_lds.csv"], work, mtime=1.0e9)
    assert counts["restored"] == 5
    assert restore_steps(sorted((published / "converge" / "steps").glob("*.json")), work, mtime=1.0e9) == [
        "step_32.json", "step_48.json"]


@pytest.mark.parametrize("damage", ["edit", "truncate", "step"])
def test_a_tampered_published_file_is_refused_before_any_case_is_restored(published, tmp_path, damage):
    table = published / "cases_lds.csv"
    if damage == "edit":  # one digit of one MFR changed by hand
        text = table.read_text()
        i = text.index(",ok,") + 6
        table.write_text(text[:i] + ("1" if text[i] != "1" else "2") + text[i + 1:])
        victim = table
    elif damage == "truncate":
        table.write_bytes(table.read_bytes()[: table.stat().st_size // 2])
        victim = table
    else:
        victim = published / "converge" / "steps" / "step_48.json"
        victim.write_text(victim.read_text().replace('"stop": false', '"stop": true'))
    work = tmp_path / "work"
    (work).mkdir()
    (work / "Snakefile").write_text("")
    tool = subprocess.run([PYTHON, str(ROOT / "tools" / "restore_study.py"), str(work), "--published", str(published)],
                          capture_output=True, text=True, timeout=120)
    assert tool.returncode == 2
    assert f"{victim} does not match its published checksum in {published / 'SHA256SUMS'}" in tool.stderr
    assert "tools/publish_checksums.py" in tool.stderr and "git checkout" in tool.stderr
    assert not (work / "results").exists()  # nothing restored, not even the intact files
    if damage != "step":
        with pytest.raises(PublishedFileError, match="changed since it was published"):
            restore_cases([table], work, mtime=1.0e9)
        assert not (work / "results").exists()
    # re-published on purpose: it goes through
    assert republish_if_listed(victim) == published / "SHA256SUMS"
    assert check_folder(published) == []


def test_a_restored_case_whose_metrics_record_rotted_is_restored_again(published, tmp_path):
    """A restored case counts as restored only while its metrics.json is whole; a truncated one
    is written again from the published row (not left to be read, nor re-run with YADE)."""
    work = tmp_path / "work"
    restore_cases([published / "cases_lds.csv"], work, mtime=1.0e9)
    cid = pd.read_csv(published / "cases_lds.csv")["case_id"][2]
    metrics = work / "results" / "cases" / cid / "metrics.json"
    whole = metrics.read_text()
    metrics.write_text(whole[: len(whole) // 3])
    counts = restore_cases([published / "cases_lds.csv"], work, mtime=1.0e9)
    assert counts["restored"] == 1 and counts["already"] == 4 and metrics.read_text() == whole


def test_a_resume_from_a_published_csv_checks_it_and_a_rewrite_re_publishes_it(published, tmp_path):
    """benchmarks/precision.py --resume-csv reads a CSV through verified_bytes(required=False): a
    published one (listed in a manifest) must match, one never published is read as it is; its
    --csv rewrite of a published table re-makes the manifest (republish_if_listed)."""
    table = published / "cases_lds.csv"
    assert verified_bytes(table, required=False) == table.read_bytes()
    table.write_bytes(table.read_bytes().replace(b",ok,", b",failed,", 1))
    with pytest.raises(PublishedFileError, match="does not match its published checksum"):
        verified_bytes(table, required=False)
    assert republish_if_listed(table) == published / "SHA256SUMS" and verified_bytes(table) == table.read_bytes()
    loose = tmp_path / "run.csv"
    loose.write_text("a\n1\n")
    assert verified_bytes(loose, required=False) == b"a\n1\n" and republish_if_listed(loose) is None


def test_a_table_without_a_published_checksum_is_refused(tmp_path):
    table = tmp_path / "cases_x.csv"
    keyed_table(pd.read_csv(STUDY / "cases_lds.csv").head(2), study_config()).to_csv(table, index=False)
    with pytest.raises(PublishedFileError, match=r"no SHA256SUMS beside it .*tools/publish_checksums.py"):
        restore_cases([table], tmp_path / "work", mtime=1.0e9)
    write_manifest(tmp_path)
    (tmp_path / "cases_y.csv").write_bytes(table.read_bytes())  # published after the manifest
    with pytest.raises(PublishedFileError, match=r"cases_y.csv is not listed in"):
        restore_cases([tmp_path / "cases_y.csv"], tmp_path / "work", mtime=1.0e9)
    assert check_folder(tmp_path) == [f"{tmp_path / 'cases_y.csv'}: not listed in {tmp_path / 'SHA256SUMS'}"]
    assert restore_cases([table], tmp_path / "work", mtime=1.0e9)["restored"] == 2


# ------------------------------------------------------------------------------------------------
# truncated and corrupt files
# ------------------------------------------------------------------------------------------------
RAW = {"format": "spreadmap-raw-1", "status": "ok", "reason": "", "params": {"case_id": "x", "f": 0.3}, "steps": 100}
METRICS = {"case_id": "x", "preset": "smoke", "status": "ok", "mfr": 0.3, "pd": 0.31}


@pytest.mark.parametrize("cut", [1, 0.5, 0.999])
def test_a_truncated_raw_or_metrics_record_is_refused(tmp_path, cut):
    for reader, record in ((read_raw, RAW), (read_metrics, METRICS)):
        text = json.dumps(record, indent=1)
        path = tmp_path / "record.json"
        path.write_text(text[: max(1, int(len(text) * cut)) if cut != 1 else 1])
        with pytest.raises(CorruptFileError, match=rf"{path}: .*(not valid JSON|empty).*not read as data"):
            reader(path)
        path.write_text(text)
        assert reader(path) == record


@pytest.mark.parametrize("content, why", [
    ("", "empty raw YADE record"), ("[1, 2]", "not a JSON object (a list)"), ("null", "not a JSON object"),
    ('{"format": "spreadmap-raw-1", "status": "ok"}', "lacks params"),
    ('{"format": "other", "status": "ok", "params": {}}', "not a raw YADE record"),
    (b'{"format": "spreadmap-raw-1", "st\xff\xfe', "not UTF-8"),
])
def test_a_damaged_raw_record_is_never_reused(tmp_path, content, why):
    """The launcher's re-use of a finished simulation (simulated.json) treats a damaged record as
    none: the case runs again (a JSON list or null had crashed it with an AttributeError)."""
    path = tmp_path / "simulated.json"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(CorruptFileError, match=re.escape(why)):
        read_raw(path)
    assert finished_simulation(path, {}) is None
    path.write_text(json.dumps({**RAW, "params": {}}))
    assert finished_simulation(path, {})["status"] == "ok"


def test_a_truncated_metrics_record_never_becomes_a_table_row(tmp_path):
    good, bad = tmp_path / "a.json", tmp_path / "b.json"
    rows = pd.read_csv(STUDY / "cases_lds.csv").head(2).to_dict("records")
    good.write_text(json.dumps(case_record(rows[0])[0]))
    bad.write_text(json.dumps(case_record(rows[1])[0])[:400])
    labels = [{"sweep": "lds", "index": 0}, {"sweep": "lds", "index": 1}]
    with pytest.raises(CorruptFileError, match=rf"{bad}: metrics record is not valid JSON, truncated"):
        build_table([good, bad], [tmp_path / "none.tsv"] * 2, labels)
    assert len(build_table([good], [tmp_path / "none.tsv"], labels[:1])) == 1


@pytest.mark.parametrize("cut", ["mid_row", "mid_number", "mid_quote"])
def test_a_half_written_table_is_refused(tmp_path, cut):
    table = pd.read_csv(STUDY / "cases_lds.csv").head(4)
    path = tmp_path / "t.csv"
    table.to_csv(path, index=False)
    text = path.read_text()
    assert read_table(path).equals(current_columns(pd.read_csv(path)))  # the layer fill under its name now
    last = text.rstrip("\n").rsplit("\n", 1)[0] + "\n"  # whole rows only
    cuts = {"mid_row": last + text[len(last): len(last) + 60],  # pandas pads the short row with NaN
            "mid_number": text[: text.rindex(".") + 3],  # a number cut short: a wrong number
            "mid_quote": last + '"open quote,1,2\n'}
    path.write_text(cuts[cut])
    with pytest.raises(CorruptFileError, match=rf"{path}: .*(ends mid-row|fields, the header|not a CSV)"):
        read_table(path)


def run_as_snakemake_job(code: str, tmp_path) -> subprocess.CompletedProcess:
    """Run `code` as a Snakemake job's script would: after spreadmap.logs.log_to (a stub of
    Snakemake's object with a log file)."""
    prelude = textwrap.dedent(f"""
        import types
        from spreadmap.logs import log_to
        snakemake = types.SimpleNamespace(log=[{str(tmp_path / 'job.log')!r}])
        log_to(snakemake)
    """)
    return subprocess.run([PYTHON, "-c", prelude + textwrap.dedent(code)], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)


def test_a_job_that_meets_a_half_written_table_moves_it_aside_with_one_line(tmp_path):
    table = tmp_path / "t.csv"
    table.write_text("a,b\n1,2\n3,")
    job = run_as_snakemake_job(f"from spreadmap.records import read_table\nread_table({str(table)!r})\n", tmp_path)
    assert job.returncode == 1 and "Traceback" not in job.stderr
    assert job.stderr.count("\n") == 1 and f"Moved it aside to {table}.corrupt; run snakemake again" in job.stderr
    assert not table.exists() and (tmp_path / "t.csv.corrupt").read_text() == "a,b\n1,2\n3,"
    assert "Moved it aside" in (tmp_path / "job.log").read_text()
    # any other error keeps its traceback
    other = run_as_snakemake_job("raise KeyError('x')\n", tmp_path)
    assert other.returncode == 1 and "Traceback" in other.stderr and "KeyError" in other.stderr


# the saved model ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def saved_model_file(tmp_path_factory):
    """The study's committed surrogate saved again (a sidecar with the file's checksum)."""
    from spreadmap.surrogate.saved_model import load_model, save_model

    path = tmp_path_factory.mktemp("model") / "model.joblib"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # a scikit-learn version other than the study's
        save_model(load_model(STUDY / "surrogate" / "model.joblib"), path)
    return path


@pytest.mark.parametrize("damage", ["truncate_half", "truncate_tail", "flip_byte", "zeros"])
def test_a_corrupted_saved_model_is_refused_and_moved_aside_by_a_job(saved_model_file, tmp_path, damage):
    from spreadmap.surrogate.saved_model import CorruptModelError, load_model, sidecar_path

    path = tmp_path / "model.joblib"
    shutil.copyfile(saved_model_file, path)
    shutil.copyfile(sidecar_path(saved_model_file), sidecar_path(path))
    assert load_model(path).targets  # intact: loads
    data = bytearray(path.read_bytes())
    if damage == "truncate_half":
        data = data[: len(data) // 2]
    elif damage == "truncate_tail":
        data = data[:-10]
    elif damage == "flip_byte":  # inside the weights: unpickles, with one wrong number
        data[len(data) // 2] ^= 0x01
    else:
        data[1000:5000] = bytes(4000)
    path.write_bytes(bytes(data))
    with pytest.raises(CorruptModelError, match=rf"{re.escape(str(path))} is not .*truncated or corrupted.*retrain"):
        load_model(path)
    if damage.startswith("truncate"):  # without the checksum, too: unpickling fails, one line
        sidecar_path(path).unlink()
        with pytest.raises(CorruptModelError, match="truncated or corrupted"):
            load_model(path)
    job = run_as_snakemake_job(f"from spreadmap.surrogate import load_model\nload_model({str(path)!r})\n", tmp_path)
    assert job.returncode == 1 and "Traceback" not in job.stderr and "Moved it aside" in job.stderr
    assert not path.exists() and (tmp_path / "model.joblib.corrupt").exists()


# Snakemake re-makes what was moved aside ----------------------------------------------------------
@pytest.mark.slow  # six Snakemake starts: 38 s on this machine, 81 s beside two YADE runs on 2 cores
def test_snakemake_remakes_a_truncated_metrics_or_raw_record_instead_of_reading_it(tmp_path):
    """A chosen point's case on disk as a finished run leaves it, but with a truncated metrics.json:
    the table job refuses it and moves it aside, and the next plan re-makes it from the raw record;
    then the raw.json truncated: the metrics job does the same, and the next plan re-runs the case.
    Each run is checked by a dry run first to plan no YADE run."""
    wf = make_workflow(tmp_path, {"points": {"named": {"one": {"f": 0.3, "d_um": 40, "h_um": 65, "v_mm_s": 10}}},
                                  "pictures": {"cases": [], "vtk": []}, "preset": "smoke"}, ("points", "pictures"))
    dry = snakemake(wf, "-n", "results/tables/points.csv")
    assert dry.returncode == 0, dry.stderr[-3000:]
    (cid,) = set(re.findall(r"results/cases/([^/\s]+)/raw\.json", dry.stdout))
    case = wf / "results" / "cases" / cid
    case.mkdir(parents=True)
    raw = json.dumps({**RAW, "params": {"case_id": cid}}, indent=1)
    files = {"case.py": "# rendered\n", "raw.json": raw[:-30], "benchmark.tsv": "s\tmax_rss\n1.0\t100\n",
             "metrics.json": json.dumps({**METRICS, "case_id": cid}, indent=1)[:50]}
    base = time.time() - 600  # in the order the workflow makes them, older than now
    for k, (name, text) in enumerate(files.items()):
        (case / name).write_text(text)
        os.utime(case / name, (base + k, base + k))

    mtime = ("--rerun-triggers", "mtime")  # files made by hand have no provenance records

    def plan(target):
        dry = snakemake(wf, "-n", target, *mtime)
        assert dry.returncode == 0, dry.stdout[-3000:]
        return planned_jobs(dry.stdout)

    assert plan("results/tables/points.csv") == {"results_table": 1, "total": 1}
    table = snakemake(wf, "results/tables/points.csv", *mtime)
    assert table.returncode != 0 and not (wf / "results" / "tables" / "points.csv").exists()
    log = (wf / "logs" / "table" / "points.log").read_text()
    assert "metrics record is not valid JSON" in log and "Moved it aside" in log and "Traceback" not in log, log
    assert (case / "metrics.json.corrupt").exists() and not (case / "metrics.json").exists()
    # re-made from the raw record, not read
    assert plan("results/tables/points.csv") == {"case_metrics": 1, "results_table": 1, "total": 2}
    metrics = snakemake(wf, f"results/cases/{cid}/metrics.json", *mtime)
    assert metrics.returncode != 0
    log = (case / "metrics.log").read_text()
    assert "raw YADE record is not valid JSON, truncated" in log and "Traceback" not in log, log
    assert (case / "raw.json.corrupt").exists() and not (case / "raw.json").exists()
    jobs = plan("results/tables/points.csv")  # the case runs again
    assert jobs["run_case"] == 1 and jobs["case_metrics"] == 1 and jobs["results_table"] == 1, jobs


# ------------------------------------------------------------------------------------------------
# a full disk while a table is written
# ------------------------------------------------------------------------------------------------
FULL_DISK = """
import resource, signal, sys
import pandas as pd
from spreadmap.files import write_text_atomically
from spreadmap.table import write_table

signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails with EFBIG instead of killing us
resource.setrlimit(resource.RLIMIT_FSIZE, (__LIMIT__, __LIMIT__))
big = pd.DataFrame({"case_id": [f"case-{i:06d}" for i in range(20000)], "mfr": 0.123456789})
try:
    if __WRITER__ == "table":
        write_table(big, __PATH__)
    else:
        write_text_atomically(__PATH__, big.to_csv(index=False))
except OSError as error:
    print(error.errno)
    print(error)
    sys.exit(3)
"""


@pytest.mark.parametrize("writer", ["table", "text"])
def test_a_full_disk_while_a_table_is_written_leaves_the_previous_table(tmp_path, writer):
    path = tmp_path / "tables" / "lds.csv"
    path.parent.mkdir()
    shutil.copyfile(STUDY / "cases_lds.csv", path)  # the previous table, ~200 kB
    before = path.read_bytes()
    limit = 64 * 1024
    assert len(before) > limit  # a file-size limit blocks only writing beyond it
    code = FULL_DISK.replace("__LIMIT__", str(limit)).replace("__WRITER__", repr(writer)).replace("__PATH__", repr(str(path)))
    run = subprocess.run([PYTHON, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert run.returncode == 3, run.stdout + run.stderr
    number, message = run.stdout.split("\n", 1)
    assert int(number) == errno.EFBIG
    assert path.read_bytes() == before  # byte for byte
    assert sorted(p.name for p in path.parent.iterdir()) == ["lds.csv"]  # no temporary file left
    assert str(path) in message and "file-size limit" in message and "left as it was" in message, message
