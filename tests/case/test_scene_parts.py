"""One home for a scene (issue 65, item 2): spreadmap.case.scene.scene_parameters is its parts (the run,
the spheres' physics, the measurement window, the domain, the time stepping), each read once from the
validated config. The shipped scene's PARAMS are what they were before the split; the template's
PARAMS block has the keys the product emits; a new material parameter is a line in three files (and
its recipe's doc). Pure Python: no YADE."""
import copy
import inspect
import json
import re

import yaml
from conftest import ROOT

from spreadmap import config as spreadmap_config
from spreadmap.case import scene
from spreadmap.case.identity import case_id, case_scene
from spreadmap.case.render import TEMPLATE, render, rendered_params, template_sha256

BEFORE = ROOT / "tests" / "data" / "scene_params_before_split.json"
# what a case's PARAMS gained since the snapshot, at the values that simulate what it did
ADDED_SINCE = {"side_walls_adhesive": True}  # issue 64: the default, the walls as before
POINT = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}


def test_the_shipped_scene_is_the_one_before_its_split():
    """The snapshot's config (the shipped one of 2026-12-07, validated then) gives the same PARAMS,
    to the bit, at three points x two presets, but for the id and the template's hash."""
    before = json.loads(BEFORE.read_text())
    config = spreadmap_config.validate(copy.deepcopy(before["config"]))
    for case in before["cases"]:
        _, params = case_scene(case["point"], case["preset"], config)
        now = {k: v for k, v in json.loads(json.dumps(params)).items() if k not in ("case_id", "scene_sha256")}
        assert now == {**case["params"], **ADDED_SINCE}, (case["point"], case["preset"])


def test_the_templates_params_block_has_the_keys_the_product_emits(config):
    """The demo PARAMS at the top of yade_scripts/spreading_case.py: the same key set as a case's
    (the benchmarks' switches `timing` and `move_steps_limit`, read with P.get, are not in it)."""
    demo = rendered_params(TEMPLATE.read_text())
    for preset in ("default", "smoke"):
        _, params = case_scene(POINT, preset, config)
        assert set(demo) == set(params), (sorted(set(demo) - set(params)), sorted(set(params) - set(demo)))


def test_the_scene_restates_no_default_of_the_schema():
    """Each value is read from the validated config: no `.get(key, literal)` fallback in the parts."""
    source = inspect.getsource(scene)
    assert not re.findall(r"\.get\(\"[a-z_0-9]+\", ", source)


def test_a_new_material_parameter_touches_at_most_four_files(config, tmp_path, monkeypatch):
    """The recipe (docs/guide/06-workflow.md, "Adding a material parameter") with a toy one,
    `material.toy_modulus_pa`: its key and default in the schema, its line in
    spreadmap.case.scene.MATERIAL, its demo value (and use) in the template, and the recipe's doc.
    It then reaches a case's PARAMS from the config's default, the rendered script, and the key."""
    touched = set()
    schema = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())
    schema["properties"]["material"]["properties"]["toy_modulus_pa"] = {"type": "number", "exclusiveMinimum": 0,
                                                                        "default": 1.0e9}
    schema_path = tmp_path / "config.schema.yaml"
    schema_path.write_text(yaml.safe_dump(schema))
    touched.add("schemas/config.schema.yaml")
    monkeypatch.setitem(scene.MATERIAL, "toy_modulus", "toy_modulus_pa")
    touched.add("spreadmap/case/scene.py")
    template = tmp_path / "spreading_case.py"
    text = TEMPLATE.read_text()
    assert text.count('    "young": ') == 1
    template.write_text(text.replace('    "young": ', '    "toy_modulus": 1.0e9,\n    "young": ', 1)
                        + '\ntoy_modulus = P["toy_modulus"]  # its use in the scene\n')
    touched.add("yade_scripts/spreading_case.py")
    touched.add("docs/guide/06-workflow.md")  # the material parameters' list
    assert len(touched) <= 4

    raw = yaml.safe_load((ROOT / "config.yaml").read_text())
    toy = spreadmap_config.validate(copy.deepcopy(raw), schema_path)
    assert toy["material"]["toy_modulus_pa"] == 1.0e9  # the schema's default, filled
    sha = template_sha256(template)
    cid, params = case_scene(POINT, "default", toy, scene_sha256=sha)
    assert params["toy_modulus"] == 1.0e9
    assert set(rendered_params(template.read_text())) == set(params)
    assert rendered_params(render(params, template))["toy_modulus"] == 1.0e9
    stiffer = copy.deepcopy(toy)
    stiffer["material"]["toy_modulus_pa"] = 2.0e9
    assert case_id(POINT, "default", stiffer, scene_sha256=sha) != cid


def test_a_config_without_the_substrate_or_rolling_sections_gets_their_keys_defaults():
    """scene.substrate and scene.rolling_resistance default to {} (issue 65), so that their keys'
    defaults are filled and the scene indexes them (before, it restated them, rolling_friction and
    stiffness_factor as 0 against the schema's 0.1 and 1)."""
    schema = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())["properties"]["scene"]["properties"]
    raw = yaml.safe_load((ROOT / "config.yaml").read_text())
    for section in ("substrate", "rolling_resistance"):
        raw["scene"].pop(section)
    scene_section = spreadmap_config.validate(raw)["scene"]
    for section in ("substrate", "rolling_resistance"):
        assert scene_section[section] == {k: v["default"] for k, v in schema[section]["properties"].items()}
