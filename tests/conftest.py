"""Shared fixtures. Tests marked `yade` run Debian's real `yade` binary on small scenes; they fail
(never skip) when it is missing: `bash tools/setup.sh` installs it."""
from __future__ import annotations

import copy
import importlib.util
import json
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import psutil
import pytest

from spreadlab.dryrun import planned_jobs  # noqa: F401  (for the workflow tests)
from spreadmap import config as spreadmap_config
from spreadmap.case.identity import case_scene
from spreadmap.case.launcher import run_case
from spreadmap.case.render import render
from spreadmap.files import write_text_atomically

ROOT = Path(__file__).resolve().parent.parent
PROCESS_TAG = "SPREADMAP_TEST_PROCESS_TAG"  # in the environment of every process a test starts
SURVIVOR_GRACE_S = 5.0  # a process a test started may take this long to end after it


def tagged_survivors(tag: str, since: float) -> list[psutil.Process]:
    """Running processes created since `since` whose environment carries `tag` (zombies, already
    dead, are not running)."""
    found = []
    for proc in psutil.process_iter(["create_time"]):
        if proc.pid == os.getpid() or (proc.info["create_time"] or 0.0) < since:
            continue
        try:
            if proc.environ().get(PROCESS_TAG) == tag and proc.status() != psutil.STATUS_ZOMBIE:
                found.append(proc)
        except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
            continue
    return found


@pytest.fixture(autouse=True)
def leaves_no_process(request):
    """Every test leaves nothing running: the processes it starts (YADE, Snakemake, its jobs, SLURM
    jobs, which inherit the environment) carry a tag of the test; any still running
    SURVIVOR_GRACE_S after the test ends (an orphan too: it keeps its environment when its parent
    dies) fails the test, and is killed. Fixtures of a wider scope (a SLURM cluster's daemons) are
    set up before this one and carry no tag."""
    tag = f"{os.getpid()}:{request.node.nodeid}"
    since = time.time() - 1.0
    os.environ[PROCESS_TAG] = tag
    try:
        yield
    finally:
        os.environ.pop(PROCESS_TAG, None)
    deadline = time.monotonic() + SURVIVOR_GRACE_S
    survivors = tagged_survivors(tag, since)
    while survivors and time.monotonic() < deadline:
        time.sleep(0.2)
        survivors = tagged_survivors(tag, since)
    if survivors:
        names = [f"{p.pid} {' '.join(p.cmdline()[:4])}" for p in survivors if p.is_running()]
        for proc in survivors:
            try:
                proc.kill()
            except psutil.NoSuchProcess:
                pass
        pytest.fail(f"the test left {len(survivors)} process(es) running (killed now): {names}")


# The test files that take longest, with their seconds (setup + call, the junit report's) in the
# full run of 2026-12-07 (1007 tests, two workers), less the cuts of that day and the next where measured (issue 52;
# only the order matters). `-n 2 --dist loadfile` hands out whole files; xdist's own order puts the
# files with the most tests first, so these few-test, long files came last and one worker ran the
# tail alone. Handed out longest first (below), the two workers end together. A file not listed counts 0.
FILE_SECONDS = {
    "tests/workflow/test_analyses_workflow.py": 200, "tests/workflow/test_faults_yade.py": 254,
    "tests/workflow/test_workflow_failures.py": 230, "tests/case/test_stability_yade.py": 200,
    "tests/workflow/test_slurm.py": 185, "tests/workflow/test_workflow.py": 160,
    "tests/fidelity/test_fidelity_workflow.py": 133, "tests/benchmarks/test_benchmarks.py": 90,
    "tests/case/test_adhesion_yade.py": 69, "tests/case/test_cases.py": 59, "tests/workflow/test_faults.py": 58,
    "tests/surrogate/test_fit_once.py": 53, "tests/workflow/test_dry_run.py": 44,
    "tests/case/test_case_cost_yade.py": 38, "tests/surrogate/test_surrogate.py": 38,
    "tests/loop/test_recheck_stop.py": 33, "tests/loop/test_convergence.py": 31, "tests/case/test_render.py": 30,
    "tests/study/test_restore.py": 28, "tests/maps/test_maps.py": 27,
    "tests/benchmarks/test_precision_benchmark.py": 27, "tests/case/test_physics_yade.py": 26,
    "tests/case/test_psd_yade.py": 25,
}


def pytest_xdist_make_scheduler(config, log):
    """Under `--dist loadfile`: whole files, the longest first (FILE_SECONDS), and a worker given its
    next file only when one test of its current file is left (xdist's own heuristic gives it at two
    left, so a worker held a queued long file behind its own last long test while the other
    one idled)."""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class LongestFileFirst(LoadFileScheduling):
        ordered = False

        def _assign_work_unit(self, node) -> None:
            if not self.ordered:  # once, before the first file is handed out; xdist's order breaks ties
                files = sorted(self.workqueue.items(), key=lambda item: -FILE_SECONDS.get(item[0], 0))
                self.workqueue.clear()
                self.workqueue.update(files)
                self.ordered = True
            super()._assign_work_unit(node)

        def _reschedule(self, node) -> None:
            if node.shutting_down:
                return
            if not self.workqueue:
                node.shutdown()
                return
            if self._pending_of(self.assigned_work[node]) > 1:  # a worker holds its last test until
                return  # it has the next one or is shut down: 1 is the lowest that never stalls it
            self._assign_work_unit(node)

    return LongestFileFirst(config, log)


@pytest.fixture(scope="session")
def config() -> dict:
    return spreadmap_config.load(ROOT / "config.yaml")


def script_module(relative: str):
    """A script of the checkout that is not in the package (tools/, benchmarks/), loaded as a module
    from its file: `relative` to the checkout's root, e.g. "tools/recheck_stop.py"."""
    path = ROOT / relative
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run_scene(params: dict, workdir: Path) -> tuple[dict, dict]:
    """Render and run one case in workdir; returns (launcher result, raw record or {})."""
    script = workdir / "case.py"
    write_text_atomically(script, render(params))
    result = run_case(script, workdir / "raw.json", workdir / "run.log", params["timeout_s"])
    raw = json.loads((workdir / "raw.json").read_text()) if (workdir / "raw.json").exists() else {}
    return result, raw


def case_params(config: dict, point: dict, preset: str = "smoke", **overrides) -> dict:
    _, params = case_scene(point, preset, config)
    params.update(overrides)
    return params


def keyed_table(table, config: dict):
    """A copy of a published cases table (a DataFrame) as a table published after content keys
    (issue 35) would be: each case id keyed for `config` and the current scene template. A stand-in
    for the restore's tests: the tables in docs/ were published before content keys."""
    from spreadmap.case.identity import case_id

    out = table.copy()
    out["case_id"] = [case_id(r, r["preset"], config, int(r["seed"])) for r in table.to_dict("records")]
    return out


def study_config() -> dict:
    """The published study's configuration (docs/study/config.yaml), validated."""
    return spreadmap_config.load(ROOT / "docs" / "study" / "config.yaml")


def run_many(jobs: list[tuple[dict, Path]], workers: int = 2) -> list[tuple[dict, dict]]:
    """Run several scenes, two at a time (one per core, single-threaded YADE)."""
    with ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(lambda job: run_scene(*job), jobs))


def with_preset(config: dict, name: str, **values) -> dict:
    """A copy of config with an extra preset `name` = smoke preset updated with values."""
    cfg = copy.deepcopy(config)
    cfg["presets"][name] = {**cfg["presets"]["smoke"], **values}
    return cfg


def finite(x) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x)


WORKFLOW_FILES = ["Snakefile", "config.yaml", "rules", "scripts", "yade_scripts", "schemas", "profiles", "envs"]
SNAKEMAKE = str(ROOT / ".venv" / "bin" / "snakemake")


def deep_update(base: dict, overrides: dict) -> dict:
    for key, value in overrides.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            deep_update(base[key], value)
        else:
            base[key] = value
    return base


def make_workflow(tmp_path: Path, overrides: dict, drop: tuple = ()) -> Path:
    """A copy of the workflow in tmp_path/wf whose config.yaml is the project's with `overrides`
    merged in and the top-level keys in `drop` removed."""
    import shutil


    wf = tmp_path / "wf"
    wf.mkdir(exist_ok=True)
    for name in WORKFLOW_FILES:
        src = ROOT / name
        if src.is_dir():
            shutil.copytree(src, wf / name, dirs_exist_ok=True)
        else:
            shutil.copy(src, wf / name)
    write_config(wf, overrides, drop)
    return wf


def write_config(wf: Path, overrides: dict, drop: tuple = ()) -> None:
    import yaml

    cfg = yaml.safe_load((ROOT / "config.yaml").read_text())
    for key in drop:
        cfg.pop(key, None)
    for section, key in REPLACED:
        if key in (overrides.get(section) or {}):
            cfg.get(section, {}).pop(key, None)
    (wf / "config.yaml").write_text(yaml.safe_dump(deep_update(cfg, copy.deepcopy(overrides)), sort_keys=False))


def snakemake(wf: Path, *args, timeout: float = 600):
    import subprocess

    return subprocess.run([SNAKEMAKE, *args], cwd=wf, capture_output=True, text=True, timeout=timeout)



# Small, fast smoke sweeps for workflow tests: large particles only (a few seconds per case).
# The workflow tests' sweeps: smoke cases of large particles (few spheres) on the study's flat floor.
# They test the workflow, not the physics; on the rough substrate a third of such smoke cases wedge
# a sphere under the blade beyond the 5 % R flag (README), which would leave the analyses too few
# usable cases.
FAST_SWEEP = {"preset": "smoke", "scene": {"substrate": {"kind": "flat"}},
              "ranges": {"d_um": {"min": 35, "max": 50}, "h_um": {"min": 55, "max": 75}},
              "points": {"named": {}}, "pictures": {"cases": [], "vtk": []},
              # the shipped powders lie below d = 35 um: outside these ranges, which the config refuses
              "decisions": {"powders": {"demo": {"f": 0.3, "d_um": 45.0}},
                            # the decisions' and the explorer's grids at their smallest that still show
                            # a region (with the shipped 21 x 21 and 7 x 9 x 17 x 21, the analysis-DAG
                            # fixture's decide and explorer jobs took 49 s and 65 s on a busy machine;
                            # it tests the workflow, not the resolution)
                            "machine": {"n_h": 5, "n_v": 5},
                            "explorer": {"n_f": 3, "n_d": 3, "n_h": 5, "n_v": 5}}}
# (section, key) pairs an override replaces instead of merging into (a mapping of names)
REPLACED = (("decisions", "powders"),)
