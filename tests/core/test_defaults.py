"""A default lives in one place, schemas/config.schema.yaml: a config without a key gets the schema's
value, the rules pass what the validated config holds, and the package's defaults (for callers
without a config) follow the schema when it changes. Expected values are read from the schema
file itself, or set here, never from the code under test."""
import copy
import json
import os
import subprocess
import sys

import pytest
import yaml
from conftest import ROOT, make_workflow, snakemake

from spreadmap.config import validate

SCHEMA = ROOT / "schemas" / "config.schema.yaml"
# the sections the rules read plainly (rules/*.smk), dropped from the shipped config below
SECTIONS = ("study_rule", "converge", "maps", "surrogate", "decisions", "pictures", "metrics")
# the keys the rules and scripts read from those sections
KEYS = [("study_rule", "tolerance"), ("study_rule", "window"), ("study_rule", "sampling_study", "seeds"),
        ("study_rule", "sampling_study", "k_max"), ("converge", "start"), ("converge", "batch"),
        ("converge", "budget"), ("metrics", "counting_noise_c"), ("maps", "powder", "h_um"),
        ("maps", "powder", "v_mm_s"), ("maps", "support", "max_distance"), ("surrogate", "model"),
        ("decisions", "confidence"), ("pictures", "colour_by"), ("pictures", "cases"), ("pictures", "vtk")]


def schema_default(schema: dict, keys) -> object:
    node = schema
    for key in keys:
        node = node["properties"][key]
    return node["default"]


def get(config: dict, keys) -> object:
    for key in keys:
        config = config[key]
    return config


@pytest.fixture(scope="module")
def schema() -> dict:
    return yaml.safe_load(SCHEMA.read_text())


def without_sections() -> dict:
    raw = yaml.safe_load((ROOT / "config.yaml").read_text())
    for name in SECTIONS:
        raw.pop(name)
    return raw


@pytest.mark.parametrize("keys", KEYS, ids=".".join)
def test_a_config_without_the_section_gets_the_schemas_default(schema, keys):
    """Before, these sections had no `default: {}`: absent, they stayed absent and each rule
    restated its own default (`CONV.get("tolerance", 0.005)`)."""
    cfg = validate(copy.deepcopy(without_sections()))
    assert get(cfg, keys) == schema_default(schema, keys)


DUMP = """include: "Snakefile"

import json as _json

with open("params.json", "w") as _fh:
    _json.dump({r.name: {k: v for k, v in r.params.items() if not callable(v)} for r in workflow.rules}, _fh,
               default=repr)
"""


def test_the_rules_pass_the_schemas_defaults(tmp_path, schema):
    """What the rules hand their scripts when the config leaves the sections out: the schema's
    values (before: the rules' own literals, and {} for whole sections such as maps and surrogate)."""
    wf = make_workflow(tmp_path, {}, drop=SECTIONS)
    (wf / "dump.smk").write_text(DUMP)
    dry = snakemake(wf, "-s", "dump.smk", "-n")
    assert dry.returncode == 0, (dry.stdout + dry.stderr)[-3000:]
    params = json.loads((wf / "params.json").read_text())
    default = lambda *keys: schema_default(schema, keys)  # noqa: E731
    step = params["converge_step"]
    assert step["tolerance"] == default("study_rule", "tolerance")
    assert step["counting_c"] == default("metrics", "counting_noise_c")
    assert step["converge"]["start"] == default("converge", "start")
    assert step["maps"]["powder"] == {"h_um": default("maps", "powder", "h_um"), "v_mm_s": default("maps", "powder", "v_mm_s")}
    assert step["surrogate"]["model"] == default("surrogate", "model")
    assert params["convergence"]["window"] == default("study_rule", "window")
    assert params["sampling_study"]["study"] == {"seeds": default("study_rule", "sampling_study", "seeds"),
                                                 "k_max": default("study_rule", "sampling_study", "k_max")}
    assert params["maps"]["counting_c"] == default("metrics", "counting_noise_c")
    assert params["decide"]["support"]["max_distance"] == default("maps", "support", "max_distance")
    assert params["decide"]["decisions"]["confidence"] == default("decisions", "confidence")
    assert params["case_picture"]["colour_by"] == default("pictures", "colour_by")


# the package's defaults for callers without a config, each at a schema path given another value here
CHANGED = {("study_rule", "tolerance"): 0.0125, ("maps", "powder", "h_um"): 61.5, ("maps", "powder", "v_mm_s"): 7.25,
           ("maps", "machine", "f"): 0.35, ("maps", "machine", "n_h"): 4, ("maps", "regime_plane", "v_mm_s"): 12.5,
           ("maps", "support", "max_distance"): 2.5, ("metrics", "counting_noise_c"): 0.41,
           ("metrics", "layer_block_d"): 3.5, ("noise_model", "n_ref"): 175, ("stability", "min_heap_h2"): 0.65,
           ("stability", "max_wedge_overlap_ratio"): 0.3, ("stability", "max_flow_trend_z"): 2.5,
           ("converge", "cost_law", "ln_a"): -17.5, ("converge", "budget"): 300, ("converge", "acquisition"): "ivr",
           ("converge", "map_error", "tolerance", "pd"): 0.03, ("converge", "ci", "halfwidth", "kurtosis"): 0.45,
           ("converge", "map_change", "box_k"): 4, ("study_rule", "floors", "skewness"): 0.75,
           ("scene", "substrate", "jitter"): 0.25}
READ = """
import inspect, json, sys
from pathlib import Path
import spreadmap.schema
spreadmap.schema.SCHEMA = Path(sys.argv[1])  # before any module reads it
from spreadmap.loop import cost, stepper
from spreadmap.loop.map_criteria import map_grids
from spreadmap.maps import grids, machine, powder_maps, regimes
from spreadmap.metrics import case
from spreadmap.noise_law import apply
from spreadmap.study_rule.rule import DEFAULT_FLOORS, DEFAULT_TOLERANCE
from spreadmap.case.substrate import floor_of
default = lambda f, name: inspect.signature(f).parameters[name].default
print(json.dumps({
    "tolerance": DEFAULT_TOLERANCE, "stepper_tolerance": default(stepper.step, "tolerance"),
    "band_h": default(powder_maps.powder_band_map, "h_um"), "cluster_v": default(powder_maps.powder_cluster_map, "v_mm_s"),
    "machine_f": default(machine.machine_map, "f"), "machine_n_h": default(machine.machine_map, "n_h"),
    "plane_v": default(regimes.regime_overlay, "v_mm_s"),
    "support": getattr(grids, "MAP_DEFAULTS", {}).get("support", {}).get("max_distance"),
    "grid_powder": map_grids()["powder"][0].tolist(), "grid_machine_rows": len(map_grids()["machine"]),
    "counting_c": default(apply.case_noise, "counting_c"), "n_ref": getattr(apply, "LAW_REFS", {}).get("n_ref"),
    "block": case.LAYER_BLOCK_D, "heap": case.MIN_HEAP_H2, "wedge": case.MAX_WEDGE_OVERLAP,
    "decline": getattr(case, "MAX_FLOW_TREND_Z", None), "ln_a": cost.DEFAULT_LAW["ln_a"],
    "step": {k: v for k, v in stepper.step_settings({}).items() if k != "criteria"},
    "criteria": stepper.step_settings(None)["criteria"], "floors": DEFAULT_FLOORS,
    "jitter": floor_of({"scene": {"substrate": {"kind": "rough"}}})[1]}))
"""


def test_the_packages_defaults_follow_the_schema(tmp_path, schema):
    """Change the schema's defaults and the package's follow (before: each restated its literal:
    57 um / 6.1 mm/s in map_grids and the powder maps, 0.005 in the study rule and the stepper...)."""
    changed = copy.deepcopy(schema)
    for keys, value in CHANGED.items():
        node = changed
        for key in keys:
            node = node["properties"][key]
        assert "default" in node, keys
        node["default"] = value
    path = tmp_path / "schema.yaml"
    path.write_text(yaml.safe_dump(changed))
    env = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    run = subprocess.run([sys.executable, "-c", READ, str(path)], capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    got = json.loads(run.stdout)
    assert got["tolerance"] == got["stepper_tolerance"] == 0.0125
    assert got["band_h"] == 61.5 and got["cluster_v"] == 7.25
    assert got["grid_powder"][2:] == [61.5, 7.25]  # NAMES order: f, d_um, h_um, v_mm_s
    assert got["machine_f"] == 0.35 and got["machine_n_h"] == 4 and got["grid_machine_rows"] == 4 * 5
    assert got["plane_v"] == 12.5 and got["support"] == 2.5
    assert got["counting_c"] == 0.41 and got["n_ref"] == 175 and got["block"] == 3.5
    assert (got["heap"], got["wedge"], got["decline"], got["ln_a"]) == (0.65, 0.3, 2.5, -17.5)
    assert (got["step"]["budget"], got["step"]["acquisition"], got["step"]["cost_law"]["ln_a"]) == (300, "ivr", -17.5)
    assert got["criteria"]["map_error"]["tolerance"]["pd"] == 0.03 and got["criteria"]["map_change"]["box_k"] == 4
    assert got["criteria"]["ci"]["halfwidth"]["kurtosis"] == 0.45
    assert got["floors"]["skewness"] == 0.75 and got["jitter"] == 0.25


def schema_defaults(node: dict):
    """What the schema states for an absent value at `node`: its default, or, for an object, the
    defaults of its properties (read from the file, not by spreadmap.schema); None: nothing."""
    if "properties" in node:
        props = {k: (schema_defaults(v), "default" in v) for k, v in node["properties"].items()}
        return {k: v for k, (v, stated) in props.items() if v is not None or stated}
    return copy.deepcopy(node.get("default"))


def test_each_settings_reader_given_nothing_returns_the_schemas_defaults(schema):
    """The package's readers of a section handed nothing (a caller without a config: a test, the
    replay, a benchmark) return the schema's defaults, every one of them, and nothing else."""
    from spreadmap.case.substrate import floor_of
    from spreadmap.loop import map_criteria, stepper
    from spreadmap.study_rule.rule import DEFAULT_FLOORS

    props = schema["properties"]
    converge = schema_defaults(props["converge"])
    step = stepper.step_settings(None)
    assert {k: v for k, v in step.items() if k != "criteria"} == converge
    criteria = {k: converge[k] for k in ("stop_on", "hold_for", "min_stop_cases", *map_criteria.CRITERIA)}
    assert step["criteria"] == map_criteria.settings({}) == criteria
    assert DEFAULT_FLOORS == schema_defaults(props["study_rule"])["floors"]
    substrate = schema_defaults(props["scene"]["properties"]["substrate"])
    assert floor_of(None) == (substrate["kind"], substrate["jitter"])


def test_a_partial_section_keeps_its_values_and_gets_the_rest_from_the_schema(schema):
    """One value given: it, and the schema's default beside it in the same object (the map
    tolerance per target); a tolerance for a target the loop does not model is refused."""
    from spreadmap.loop import map_criteria

    conv = schema["properties"]["converge"]["properties"]
    s = map_criteria.settings({"map_error": {"tolerance": {"mfr": 0.02}}})
    assert s["map_error"]["tolerance"] == {"mfr": 0.02, "pd": schema_defaults(conv["map_error"])["tolerance"]["pd"]}
    assert s["map_error"]["margin"] == conv["map_error"]["properties"]["margin"]["default"]
    with pytest.raises(ValueError, match="converge.map_error.tolerance"):
        map_criteria.settings({"map_error": {"tolerance": {"coverage": 0.1}}}, targets=("mfr", "pd"))
