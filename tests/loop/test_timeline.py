"""The run's timeline from a Snakemake log written by hand (Snakemake 9's format, as in a real
run's .snakemake/log): jobs, their cores, and the core time by kind, against numbers counted by hand."""
import pandas as pd
import pytest

from spreadmap.loop.timeline import core_time, parse_log, place_on_cores
from spreadmap.loop.timeline_plot import draw_timeline


def start(t, rule, jobid, wildcards=None, local=False):
    lines = [f"[Sun Dec  6 {t} 2026]", f"{'localrule' if local else 'rule'} {rule}:", "    output: x",
             f"    jobid: {jobid}", "    reason: Missing output files: x"]
    if wildcards:
        lines.append(f"    wildcards: {wildcards}")
    return "\n".join(lines + ["    resources: tmpdir=/tmp"])


def end(t, rule, jobid):
    return f"[Sun Dec  6 {t} 2026]\nFinished jobid: {jobid} (Rule: {rule})"


LOG = "\n".join([
    "Building DAG of jobs...",
    start("03:00:00", "render_case", 1, "case=a", local=True), end("03:00:01", "render_case", 1),
    start("03:00:01", "run_case", 2, "case=a"), start("03:00:01", "run_case", 3, "case=b"),
    end("03:01:41", "run_case", 2),                                    # a: 100 s on core 1
    start("03:01:41", "run_case", 4, "case=c"),                        # c takes core 1 as a frees it
    end("03:02:01", "run_case", 3),                                    # b: 120 s on core 2
    end("03:02:41", "run_case", 4),                                    # c: 60 s
    start("03:02:41", "converge_step", 5, "step=32", local=True), end("03:03:41", "converge_step", 5),  # 60 s
    start("03:03:41", "surrogate", 6), start("03:03:50", "run_case", 7, "case=d"),  # d never finishes
    end("03:04:41", "surrogate", 6),
    "[Sun Dec  6 03:05:01 2026]", "Error in rule run_case:",
])


def test_jobs_their_cores_and_the_core_time_by_kind():
    jobs = parse_log(LOG)
    assert list(jobs["rule"]) == ["render_case", "run_case", "run_case", "run_case", "converge_step", "surrogate", "run_case"]
    assert list(jobs["wildcards"][:3]) == ["case=a", "case=a", "case=b"]
    placed = place_on_cores(jobs)
    lanes = dict(zip(placed["jobid"], placed["lane"]))
    assert lanes == {1: -1, 2: 0, 3: 1, 4: 0, 5: 0, 6: 0, 7: 1}  # b still holds core 2 until 03:02:01
    assert list(placed["seconds"]) == [1, 100, 120, 60, 60, 60, 71]
    assert list(placed["finished"]) == [True] * 6 + [False]  # d ends at the log's last stamp
    summary = core_time(placed, cores=2)
    assert summary["wall_s"] == 301                       # 03:00:00 to 03:05:01
    assert summary["DEM_case_s"] == 100 + 120 + 60 + 71
    assert summary["loop_step_s"] == 60 and summary["analysis_s"] == 60
    assert summary["idle_s"] == 2 * 301 - (351 + 120)
    assert summary["idle_share"] == pytest.approx(131 / 602)
    assert summary["lanes"] == 2 and summary["unfinished"] == 1
    assert core_time(placed, None) == summary  # no core count (a cluster run): the most jobs at once, 2


def test_the_figure_redraws_from_its_numbers(tmp_path):
    placed = place_on_cores(parse_log(LOG))
    paths = draw_timeline(placed, core_time(placed, 2), tmp_path / "timeline", "test")
    table = pd.read_csv(paths["csv"])
    assert len(table) == 7 and table["end_min"].max() == pytest.approx(301 / 60)
    assert paths["png"].stat().st_size > 10_000
