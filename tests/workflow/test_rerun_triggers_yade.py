"""A finished case is never re-run for what its id leaves out (issue 65): one smoke case through the
real workflow and YADE, then a longer `timeout_s` plans nothing (Snakemake's params trigger does not
see the scene: spreadmap.case.identity.SceneParams), while a changed Young's modulus plans the case
anew under its new id."""
from __future__ import annotations

import re

import pytest
import yaml
from conftest import make_workflow, planned_jobs, snakemake

TARGET = "results/tables/points.csv"


@pytest.mark.yade
def test_a_longer_timeout_reruns_nothing_a_new_modulus_reruns_the_case(tmp_path):
    wf = make_workflow(tmp_path, {"points": {"named": {"one": {"f": 0.3, "d_um": 45, "h_um": 65, "v_mm_s": 10}}},
                                  "pictures": {"cases": [], "vtk": []}, "preset": "smoke",
                                  "scene": {"substrate": {"kind": "flat"}}}, ("points", "pictures"))
    run = snakemake(wf, "--cores", "1", TARGET)
    assert run.returncode == 0, run.stderr[-3000:]
    (first,) = {p.name for p in (wf / "results" / "cases").iterdir()}

    cfg = yaml.safe_load((wf / "config.yaml").read_text())
    cfg["presets"]["smoke"]["timeout_s"] = 4321.0
    (wf / "config.yaml").write_text(yaml.safe_dump(cfg, sort_keys=False))
    dry = snakemake(wf, "-n", TARGET)
    assert dry.returncode == 0, dry.stderr[-3000:]
    jobs = planned_jobs(dry.stdout)
    assert "run_case" not in jobs and "render_case" not in jobs, dry.stdout[-3000:]

    cfg["material"]["young_pa"] = 2.0e9
    (wf / "config.yaml").write_text(yaml.safe_dump(cfg, sort_keys=False))
    dry = snakemake(wf, "-n", TARGET)
    assert dry.returncode == 0, dry.stderr[-3000:]
    assert planned_jobs(dry.stdout).get("run_case") == 1
    (second,) = set(re.findall(r"results/cases/([^/\s]+)/raw\.json", dry.stdout))
    assert second != first
