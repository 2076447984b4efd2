"""Cases of the scene template before adhesion (issue 49), and cases that read the peak overlap every
step (before issue 50's stride), carried to today's ids without re-running: the carried id is the one
the workflow computes from scratch for the same point (spreadmap.case.identity.case_id), and nothing
else is touched."""
import copy
import json

from spreadmap.case.identity import case_id, keyed_id
from spreadmap.case.migrate import EQUIVALENT_TEMPLATES, carry_to_current_template
from spreadmap.case.render import template_sha256

OLD = "2faa01e6a62c2a28"  # the template before adhesion
POINT = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}


def test_the_listed_equivalence_leads_to_todays_template():
    """Whoever changes the scene template decides whether the old cases still carry over (and
    updates EQUIVALENT_TEMPLATES): until then this fails."""
    assert all(new == template_sha256() for new, _ in EQUIVALENT_TEMPLATES.values())


def old_record(config, tmp_path, point=POINT, template=OLD):
    """A finished case folder as an earlier template wrote it (before adhesion: without its parameters)."""
    from spreadmap.case.identity import case_scene

    _, params = case_scene(point, "default", config)
    size_keys = ("size_span", "psd_sizes", "psd_cumulative")  # added by the size distribution (issue 51)
    dropped = (size_keys if template != template_sha256() else ()) + (
        ("surface_energy", "adhesion_gamma") if template == OLD else ())
    params = {k: v for k, v in params.items() if k not in dropped}
    params["scene_sha256"] = template
    params["overlap_every"] = max(1, int(params["contact_time"] / (8.0 * params["time_step"])))  # before issue 50
    old_id = keyed_id(params)
    params["case_id"] = old_id
    folder = tmp_path / "results" / "cases" / old_id
    folder.mkdir(parents=True)
    (folder / "raw.json").write_text(json.dumps({"params": params, "status": "ok"}))
    (folder / "run.log").write_text(f"[{old_id}] done\n")
    return folder


def test_a_dry_case_of_the_old_template_gets_todays_id(config, tmp_path):
    dry = copy.deepcopy(config)
    dry["material"]["surface_energy_j_m2"] = 0.0
    folder = old_record(dry, tmp_path)
    cases = folder.parent
    other = cases / "default-f0.3000-d30.000-h65.000-v10.0000-s1-0123abcd"  # another template: untouched
    other.mkdir()
    (other / "raw.json").write_text(json.dumps({"params": {"scene_sha256": "ffffffffffffffff"}}))
    mtime = (folder / "run.log").stat().st_mtime_ns
    report = carry_to_current_template(cases, config)
    want = case_id(POINT, "default", dry)
    assert report == {"renamed": [(folder.name, want)], "left": []}
    assert sorted(p.name for p in cases.iterdir()) == sorted([want, other.name])
    assert (cases / want / "run.log").read_text() == f"[{want}] done\n"
    assert (cases / want / "run.log").stat().st_mtime_ns == mtime
    assert carry_to_current_template(cases, config) == {"renamed": [], "left": []}  # a second run: nothing to do
    # the adhesive default asks for another case: the dry one is kept beside it, not taken for it
    assert want != case_id(POINT, "default", config)


def test_dry_run_renames_nothing(config, tmp_path):
    folder = old_record(config, tmp_path)
    report = carry_to_current_template(folder.parent, config, dry_run=True)
    assert len(report["renamed"]) == 1 and folder.exists()


def test_an_adhesive_case_of_the_first_adhesive_template_keeps_its_surface_energy(config, tmp_path):
    """The template of the main job of 2026-12-06, before a comment was corrected: its adhesive
    cases carry to the ids today's adhesive default asks for."""
    folder = old_record(config, tmp_path, template="0ae31d5c9de2bce9")
    report = carry_to_current_template(folder.parent, config)
    assert report == {"renamed": [(folder.name, case_id(POINT, "default", config))], "left": []}


def test_an_adhesive_case_of_the_template_before_the_size_distribution_gets_todays_one_size_id(config, tmp_path):
    """The adhesion template as corrected (e9640a66ef79dc3a), before the size distribution: its
    one-size cases carry to the ids of today's one-size default."""
    assert config["material"]["size_distribution"]["span"] == 0.0
    folder = old_record(config, tmp_path, template="e9640a66ef79dc3a")
    report = carry_to_current_template(folder.parent, config)
    assert report == {"renamed": [(folder.name, case_id(POINT, "default", config))], "left": []}


def test_a_case_of_todays_template_read_every_step_gets_todays_id(config, tmp_path):
    """The published cases of template 7069f5e574fa3095 read the peak overlap every step (1 at
    `default`); today's scene reads it every 2: the same spheres to the bit, another id. Carried;
    its raw record keeps overlap_every 1, which its metrics read."""
    folder = old_record(config, tmp_path, template=template_sha256())
    assert json.loads((folder / "raw.json").read_text())["params"]["overlap_every"] == 1
    want = case_id(POINT, "default", config)
    assert folder.name != want
    report = carry_to_current_template(folder.parent, config)
    assert report == {"renamed": [(folder.name, want)], "left": []}
    carried = json.loads((folder.parent / want / "raw.json").read_text())["params"]
    assert carried["overlap_every"] == 1 and carried["case_id"] == want
    assert carry_to_current_template(folder.parent, config) == {"renamed": [], "left": []}
