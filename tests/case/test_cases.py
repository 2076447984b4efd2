"""Case identity by content (spreadmap/case/identity.py, issue 35): every parameter that changes a simulation
keys the case, nothing else does; two materials' cases sit side by side in one results folder and
a switch back re-uses them; folders named before content keys are migrated without re-running
(spreadmap/case/migrate.py, tools/migrate_case_ids.py). The workflow tests run two real smoke
cases with YADE (a few seconds each); the rest are dry runs."""
import copy
import json
import os
import re
import shutil
import subprocess
import sys

import pytest
import yaml
from conftest import FAST_SWEEP, ROOT, deep_update, make_workflow, planned_jobs, snakemake

from spreadmap import config as spreadmap_config
from spreadmap.case.identity import (
    CASE_ID_PATTERN,
    LEGACY_CASE_ID_PATTERN,
    case_id,
    case_scene,
    content_key,
    readable_id,
    readable_part,
)
from spreadmap.case.migrate import legacy_case_folders, migrate_case_folders
from spreadmap.case.render import render, template_sha256

POINT = {"f": 0.31544, "d_um": 16.0712, "h_um": 57.8541, "v_mm_s": 8.01083}


def test_a_case_id_shows_its_design_point_then_its_content_key(config):
    cid, params = case_scene(POINT, "default", config)
    assert re.fullmatch(CASE_ID_PATTERN, cid) and not re.fullmatch(LEGACY_CASE_ID_PATTERN, cid)
    assert cid.startswith("default-f0.3154-d16.071-h57.854-v8.0108-s1-") and params["case_id"] == cid
    assert readable_part(cid) == readable_id(POINT, "default", 1) == "default-f0.3154-d16.071-h57.854-v8.0108-s1"
    assert cid.endswith("-" + content_key(params)) and params["scene_sha256"] == template_sha256()
    assert case_id(POINT, "default", config, seed=2).startswith("default-f0.3154-d16.071-h57.854-v8.0108-s2-")
    # the design point as simulated: a point that rounds to the same one is the same case
    assert case_id({k: v + 1e-6 for k, v in POINT.items()}, "default", config) == cid


def _changed(config, path, value):
    cfg = copy.deepcopy(config)
    node = cfg
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return cfg


@pytest.mark.parametrize("path, value", [
    (("material", "density_kg_m3"), 4430.0),
    (("material", "young_pa"), 1.0e9),
    (("material", "restitution"), 0.5),
    (("scene", "substrate", "kind"), "flat"),
    (("scene", "fed_heap"), False),  # the shipped scene feeds the heap
    (("scene", "feed_transient"), True),  # the pile without the transient's passing
    (("presets", "default", "pile_transient_d"), 2.0),  # the pile sized for a shorter transient
    (("scene", "settle_damping"), 0.3),
    (("presets", "default", "width_d"), 4.0),
    (("presets", "default", "dt_factor"), 0.2),
    (("metrics", "counting_noise_c"), 0.5),  # it sizes a precision preset's window
])
def test_the_key_changes_with_whatever_changes_the_simulation(config, path, value):
    cid = case_id(POINT, "default", config)
    other = case_id(POINT, "default", _changed(config, path, value))
    assert other != cid and readable_part(other) == readable_part(cid), path


def test_the_key_changes_with_the_scene_template(config):
    assert case_id(POINT, "default", config, scene_sha256="0" * 16) != case_id(POINT, "default", config)


@pytest.mark.parametrize("path, value", [
    (("material", "young_pa"), 2.0e9),
    (("presets", "default", "density_scale"), 10.0),
    (("material", "surface_energy_j_m2"), 0.0),
    (("material", "poisson"), 0.25),
])
def test_a_changed_physical_value_re_keys(config, path, value):
    assert _changed(config, path, value) != config
    assert case_id(POINT, "default", _changed(config, path, value)) != case_id(POINT, "default", config), path


def test_the_friction_re_keys(config):
    """f is in the readable part and in the key (the parameter `friction`)."""
    _, params = case_scene(POINT, "default", config)
    assert content_key({**params, "friction": 0.4}) != content_key(params)


@pytest.mark.parametrize("path, value", [
    (("scene", "timeout_factor"), 60),  # the outer timeout
    (("scene", "progress_every_s"), 1.0),  # the log's progress cadence
    (("presets", "default", "timeout_s"), 7200),
])
def test_the_key_ignores_the_cases_bookkeeping(config, path, value):
    """The launcher's timeout, the log's progress cadence and the step estimate it prints keep a
    case's books: the same simulation, the same id (issue 65)."""
    cid, params = case_scene(POINT, "default", config)
    other_id, other = case_scene(POINT, "default", _changed(config, path, value))
    assert other != params and other_id == cid, path
    assert content_key({**params, "estimated_steps": 1}) == content_key(params)


def _template_copy(tmp_path, edit):
    template = tmp_path / "spreading_case.py"
    template.write_text(edit((ROOT / "yade_scripts" / "spreading_case.py").read_text()))
    return template


@pytest.mark.parametrize("edit", [
    lambda t: t + "\n# a comment at the end\n",
    lambda t: t.replace("import json\n", "import json  # a comment on an import\n", 1),
    lambda t: t.replace('"""Lay the rough substrate up to x_to', '"""Lay the rough substrate (reworded) up to x_to', 1),
    lambda t: t.replace('"case_id": "demo",', '"case_id": "another demo", "gap": 1e-4,', 1),  # the demo PARAMS
])
def test_a_comment_docstring_or_demo_value_in_the_template_keeps_every_id(config, tmp_path, edit):
    from spreadmap.case.render import template_sha256

    template = _template_copy(tmp_path, edit)
    assert template.read_text() != (ROOT / "yade_scripts" / "spreading_case.py").read_text()
    assert template_sha256(template) == template_sha256()
    assert case_id(POINT, "default", config, scene_sha256=template_sha256(template)) == case_id(POINT, "default", config)


@pytest.mark.parametrize("edit", [
    lambda t: t + "\nEXTRA = 1\n",
    lambda t: t.replace("x_lo = -tb - 20.0 * d", "x_lo = -tb - 21.0 * d", 1),
])
def test_a_code_change_in_the_template_re_keys(config, tmp_path, edit):
    from spreadmap.case.render import template_sha256

    template = _template_copy(tmp_path, edit)
    assert template_sha256(template) != template_sha256()
    assert case_id(POINT, "default", config, scene_sha256=template_sha256(template)) != case_id(POINT, "default", config)


@pytest.mark.parametrize("path, value", [
    (("maps", "resolution"), 7),
    (("surrogate",), {"kind": "something else"}),
    (("converge", "tolerance"), 0.5),
    (("decisions",), {}),
    (("regime",), {"jam_mfr": 0.2}),
    (("presets", "unused_preset"), {"dt_factor": 0.1}),
])
def test_the_key_ignores_what_does_not_change_the_simulation(config, path, value):
    assert case_id(POINT, "default", _changed(config, path, value)) == case_id(POINT, "default", config), path


def test_the_key_survives_a_last_bit_difference_and_ignores_the_name(config):
    """Another machine's libm may round a derived float differently in its last bit: the same case."""
    _, params = case_scene(POINT, "default", config)
    nudged = {**params, "contact_time": params["contact_time"] * (1 + 2 ** -52), "case_id": "anything"}
    assert content_key(nudged) == content_key(params)
    assert content_key({**params, "contact_time": params["contact_time"] * 1.001}) != content_key(params)
    # a config's 7980 and 7980.0 are one material
    as_int = _changed(config, ("material", "density_kg_m3"), int(config["material"]["density_kg_m3"]))
    as_float = _changed(config, ("material", "density_kg_m3"), float(config["material"]["density_kg_m3"]))
    assert case_id(POINT, "default", as_int) == case_id(POINT, "default", as_float)


# ------------------------------------------------------------------------------------------------
# the workflow: two materials side by side, migration of a legacy folder
# ------------------------------------------------------------------------------------------------
SMOKE = deep_update(copy.deepcopy(FAST_SWEEP), {"sweeps": {"lds": {"seed": 42, "partitions": [2]}}})
DROP = ("sweeps", "points")
TABLE = "results/tables/lds.csv"


def _set_density(wf, density):
    cfg = yaml.safe_load((wf / "config.yaml").read_text())
    cfg["material"]["density_kg_m3"] = density
    (wf / "config.yaml").write_text(yaml.safe_dump(cfg, sort_keys=False))


def _cases(wf):
    return sorted(p.name for p in (wf / "results" / "cases").iterdir())


def _planned_runs(dry):
    return set(re.findall(r"results/cases/([^/\s]+)/raw\.json", dry.stdout)) if "run_case" in planned_jobs(dry.stdout) else set()


@pytest.fixture(scope="module")
def ran_steel(tmp_path_factory):
    """The two smoke cases of a 2-point LDS sweep, run with YADE under the shipped material."""
    wf = make_workflow(tmp_path_factory.mktemp("steel"), SMOKE, DROP)
    run = snakemake(wf, TABLE, "--cores", "1")
    assert run.returncode == 0, run.stderr[-3000:]
    return wf


@pytest.mark.yade
@pytest.mark.slow
def test_two_materials_sit_side_by_side_and_a_switch_back_runs_nothing(ran_steel, tmp_path):
    wf = tmp_path / "wf"
    shutil.copytree(ran_steel, wf, symlinks=True)
    steel = _cases(wf)
    assert len(steel) == 2 and all(re.fullmatch(CASE_ID_PATTERN, c) for c in steel)
    raw = {c: (wf / "results/cases" / c / "raw.json").read_bytes() for c in steel}
    _set_density(wf, 4430.0)  # titanium's density: every case is another case
    dry = snakemake(wf, "-n", TABLE)
    assert dry.returncode == 0, dry.stderr[-3000:]
    titanium = _planned_runs(dry)
    assert len(titanium) == 2 and not titanium & set(steel)
    assert {readable_part(c) for c in titanium} == {readable_part(c) for c in steel}  # the same design points
    # the steel results are not planned to be touched, and stay as they were
    assert not any(f"results/cases/{c}/" in dry.stdout for c in steel)
    assert all((wf / "results/cases" / c / "raw.json").read_bytes() == raw[c] for c in steel)
    _set_density(wf, 7980.0)  # back to steel: its cases are found again
    back = snakemake(wf, "-n", TABLE)
    assert back.returncode == 0, back.stderr[-3000:]
    assert "run_case" not in planned_jobs(back.stdout) and "render_case" not in planned_jobs(back.stdout), back.stdout[-2000:]


def _as_legacy(folder):
    """A case folder as a run before content keys left it: named by its readable part, which is the
    id recorded inside its files (modification times kept)."""
    new = folder.name
    old = readable_part(new)
    for path in folder.rglob("*"):
        if path.is_file() and path.suffix in (".py", ".json", ".log"):
            stat = path.stat()
            path.write_text(path.read_text().replace(new, old))
            os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    folder.rename(folder.with_name(old))
    return folder.with_name(old)


@pytest.mark.yade
@pytest.mark.slow
def test_a_legacy_folder_is_migrated_to_its_content_id_and_re_used(ran_steel, tmp_path):
    """Two case folders of a run before content keys (and Snakemake's records of them gone with their
    old paths), one restored folder with no parameters, one case run under another material: the
    migration renames the three it can key to their content ids (the id inside their files with them,
    modification times kept) and leaves the restored one, reported; the workflow then runs nothing
    for the steel cases, and the titanium one sits beside them."""
    wf = tmp_path / "wf"
    shutil.copytree(ran_steel, wf, symlinks=True)
    cases = wf / "results" / "cases"
    steel = _cases(wf)
    times = {c: os.path.getmtime(cases / c / "raw.json") for c in steel}
    legacy = [_as_legacy(cases / c) for c in steel]
    # a third folder: the first case's files, as if run with titanium's density
    config = spreadmap_config.load(wf / "config.yaml")
    config["material"]["density_kg_m3"] = 4430.0
    raw = json.loads((legacy[0] / "raw.json").read_text())
    ti_id, ti_params = case_scene(raw["params"]["point"], raw["params"]["preset"], config, 7)  # seed 7: its own folder
    ti_legacy = cases / readable_part(ti_id)
    ti_params["case_id"] = ti_legacy.name
    ti_legacy.mkdir()
    (ti_legacy / "case.py").write_text(render(ti_params))
    restored = cases / readable_id(raw["params"]["point"], raw["params"]["preset"], 9)
    restored.mkdir()
    (restored / "metrics.json").write_text(json.dumps({"case_id": restored.name, "status": "ok"}))
    (restored / "restored.json").write_text("{}")
    shutil.rmtree(wf / ".snakemake" / "metadata")  # Snakemake's records were of the old paths
    (wf / TABLE).unlink()  # the table is made again from the cases (an existing one would hide them)
    assert len(legacy_case_folders(cases)) == 4
    warned = snakemake(wf, "-n", TABLE)
    assert warned.returncode == 0, warned.stderr[-3000:]
    assert "4 case folders in results/cases/ have ids without a content key" in warned.stderr
    assert planned_jobs(warned.stdout).get("run_case") == 2, warned.stdout[-3000:]  # not re-used until migrated

    tool = subprocess.run([sys.executable, str(ROOT / "tools" / "migrate_case_ids.py"), str(wf)],
                          capture_output=True, text=True, timeout=120)
    assert tool.returncode == 0, tool.stderr
    assert "3 case folders renamed, 1 left as they are" in tool.stdout
    assert f"left {restored.name}: no raw record and no case.py" in tool.stdout
    assert sorted(set(_cases(wf)) - {restored.name}) == sorted(steel + [ti_id])
    assert restored.exists() and legacy_case_folders(cases) == [restored]
    for c in steel:
        assert os.path.getmtime(cases / c / "raw.json") == times[c]
        assert json.loads((cases / c / "raw.json").read_text())["params"]["case_id"] == c
        assert json.loads((cases / c / "metrics.json").read_text())["case_id"] == c
        assert f"case parameters of {c} " in (cases / c / "case.py").read_text()
    dry = snakemake(wf, "-n", TABLE)
    assert dry.returncode == 0, dry.stderr[-3000:]
    assert "run_case" not in planned_jobs(dry.stdout) and planned_jobs(dry.stdout)["results_table"] == 1, dry.stdout[-2000:]
    assert migrate_case_folders(cases) == {"renamed": [], "left": [(restored.name, "no raw record and no case.py")]}
