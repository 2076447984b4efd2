"""Cases keyed by the scene template's bytes (issue 35 to issue 65) carried, once, to the key of what
they simulate (issue 65: the template's code, no bookkeeping fields) without re-running: the cases of
the template before adhesion (issue 49), of the adhesion templates before the size distribution, and
those that read the peak overlap every step (before issue 50's stride). The carried id is the one the
workflow computes from scratch for the same point (spreadmap.case.identity.case_id) under the
template code they are carried to, and nothing else is touched."""
import copy
import json

from spreadmap.case.identity import NAMING_FIELDS, case_id, keyed_id
from spreadmap.case.migrate import ADDED_SINCE_BYTES, BYTE_HASHED_TEMPLATES, CARRIED_TO, carry_to_code_keys

OLD = "2faa01e6a62c2a28"  # the template before adhesion
LAST_BYTES = "7069f5e574fa3095"  # the last template keyed by its bytes
POINT = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}


def old_record(config, tmp_path, point=POINT, template=OLD):
    """A finished case folder as a template keyed by its bytes wrote it (without the parameters
    added since; before adhesion, without its own), named by the key of its day (every parameter
    but the id, timeout and progress cadence included)."""
    from spreadmap.case.identity import case_scene

    _, params = case_scene(point, "default", config)
    size_keys = ("size_span", "psd_sizes", "psd_cumulative")  # added by the size distribution (issue 51)
    dropped = (*ADDED_SINCE_BYTES, *(size_keys if template != LAST_BYTES else ()),
               *(("surface_energy", "adhesion_gamma") if template == OLD else ()))
    params = {k: v for k, v in params.items() if k not in dropped}
    params["scene_sha256"] = template
    params["overlap_every"] = max(1, int(params["contact_time"] / (8.0 * params["time_step"])))  # before issue 50
    params["timeout_s"] = 1234.5  # bookkeeping: keyed then, not now
    old_id = keyed_id(params, NAMING_FIELDS)
    params["case_id"] = old_id
    folder = tmp_path / "results" / "cases" / old_id
    folder.mkdir(parents=True)
    (folder / "raw.json").write_text(json.dumps({"params": params, "status": "ok"}))
    (folder / "run.log").write_text(f"[{old_id}] done\n")
    return folder


def test_a_dry_case_of_the_template_before_adhesion_gets_todays_id(config, tmp_path):
    dry = copy.deepcopy(config)
    dry["material"]["surface_energy_j_m2"] = 0.0
    folder = old_record(dry, tmp_path)
    cases = folder.parent
    other = cases / "default-f0.3000-d30.000-h65.000-v10.0000-s1-0123abcd"  # another template: untouched
    other.mkdir()
    (other / "raw.json").write_text(json.dumps({"params": {"scene_sha256": "ffffffffffffffff"}}))
    mtime = (folder / "run.log").stat().st_mtime_ns
    report = carry_to_code_keys(cases, config)
    want = case_id(POINT, "default", dry, scene_sha256=CARRIED_TO)
    assert report == {"renamed": [(folder.name, want)], "left": []}
    assert sorted(p.name for p in cases.iterdir()) == sorted([want, other.name])
    assert (cases / want / "run.log").read_text() == f"[{want}] done\n"
    assert (cases / want / "run.log").stat().st_mtime_ns == mtime
    assert carry_to_code_keys(cases, config) == {"renamed": [], "left": []}  # a second run: nothing to do
    # the adhesive default asks for another case: the dry one is kept beside it, not taken for it
    assert want != case_id(POINT, "default", config, scene_sha256=CARRIED_TO)


def test_dry_run_renames_nothing(config, tmp_path):
    folder = old_record(config, tmp_path)
    report = carry_to_code_keys(folder.parent, config, dry_run=True)
    assert len(report["renamed"]) == 1 and folder.exists()


def test_every_listed_adhesive_template_carries_to_the_id_of_todays_one_size_default(config, tmp_path):
    """The template of the main job of 2026-12-06 (before a comment was corrected), the corrected
    one (before the size distribution) and the last one keyed by its bytes: their adhesive one-size
    cases carry to the ids today's adhesive one-size default asks for."""
    assert config["material"]["size_distribution"]["span"] == 0.0
    want = case_id(POINT, "default", config, scene_sha256=CARRIED_TO)
    for template in ("0ae31d5c9de2bce9", "e9640a66ef79dc3a", LAST_BYTES):
        folder = old_record(config, tmp_path / template, template=template)
        report = carry_to_code_keys(folder.parent, config)
        assert report == {"renamed": [(folder.name, want)], "left": []}, template
        carried = json.loads((folder.parent / want / "raw.json").read_text())["params"]
        assert carried["overlap_every"] == 1 and carried["case_id"] == want  # its record: what it ran with
        assert carry_to_code_keys(folder.parent, config) == {"renamed": [], "left": []}
    assert set(BYTE_HASHED_TEMPLATES) == {OLD, "0ae31d5c9de2bce9", "e9640a66ef79dc3a", LAST_BYTES}


def test_a_case_an_earlier_carry_renamed_is_carried_again(config, tmp_path):
    """A case of the template before adhesion that the carry of issue 49 renamed to the bytes key of
    7069f5e574fa3095 (its record keeping the parameters it ran with) is carried on to today's key."""
    dry = copy.deepcopy(config)
    dry["material"]["surface_energy_j_m2"] = 0.0
    folder = old_record(dry, tmp_path)
    params = json.loads((folder / "raw.json").read_text())["params"]
    reads = config["presets"]["default"]["overlap_reads_per_contact"]
    from spreadmap.case.migrate import with_todays_stride
    earlier = keyed_id(with_todays_stride({**params, **BYTE_HASHED_TEMPLATES[OLD], "scene_sha256": LAST_BYTES}, reads),
                       NAMING_FIELDS)
    folder = folder.rename(folder.with_name(earlier))
    report = carry_to_code_keys(folder.parent, config)
    assert report == {"renamed": [(earlier, case_id(POINT, "default", dry, scene_sha256=CARRIED_TO))], "left": []}


def test_a_folder_its_parameters_do_not_name_is_left_and_reported(config, tmp_path):
    folder = old_record(config, tmp_path, template=LAST_BYTES)
    wrong = folder.with_name(folder.name[:-8] + "deadbeef")
    folder.rename(wrong)
    report = carry_to_code_keys(wrong.parent, config)
    assert report == {"renamed": [], "left": [(wrong.name, "the parameters in raw.json are not this folder's")]}


def test_the_tool_carries_a_results_folder_once(config, tmp_path):
    """tools/migrate_case_ids.py on a workflow directory: the bytes-keyed case is renamed to today's
    id, and a second run renames nothing."""
    import shutil
    import subprocess
    import sys

    from conftest import ROOT

    folder = old_record(config, tmp_path, template=LAST_BYTES)
    shutil.copy(ROOT / "config.yaml", tmp_path / "config.yaml")
    tool = [sys.executable, str(ROOT / "tools" / "migrate_case_ids.py"), str(tmp_path)]
    first = subprocess.run(tool, capture_output=True, text=True, timeout=120)
    assert first.returncode == 0, first.stderr
    want = case_id(POINT, "default", config, scene_sha256=CARRIED_TO)
    assert f"renamed {folder.name} -> {want}" in first.stdout
    assert "1 case folders keyed by a template's bytes renamed" in first.stdout
    assert [p.name for p in folder.parent.iterdir()] == [want]
    again = subprocess.run(tool, capture_output=True, text=True, timeout=120)
    assert "0 case folders keyed by a template's bytes renamed" in again.stdout
