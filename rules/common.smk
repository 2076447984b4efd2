# Parse-time set-up: validate the configuration and register every case the targets can ask for.
# Per-case values reach the jobs as params from this registry (never through a shared table file,
# which would re-run every case whenever the table grows). A case is its content (every parameter the
# YADE script receives that reaches the simulation: design point, preset values, material, scene, packing
# seed, the template code's hash; not the timeout or the progress cadence;
# spreadmap.case.identity): the same content asked for by two sets is one case, run once, and two contents
# (two materials, two scene versions) are two cases side by side in results/cases/.
import json
import os
import sys

from spreadmap import config as spreadmap_config
from spreadmap.case.identity import CASE_ID_PATTERN, SceneParams, case_scene, rounded
from spreadmap.design import NAMES
from spreadmap.fidelity.plan import knob_cases, knob_presets, preset_cases
from spreadmap.sampling import chosen_points
from spreadmap.case.render import template_sha256
from spreadmap.case.migrate import legacy_case_folders
from spreadmap.case.scene import UnsafeTimeStep
from spreadmap.sweeps import loop_labels, planned_cases
from spreadmap.case.substrate import floor_label
from spreadmap.case.powder import powder_label
from spreadmap.surrogate.correction import Correction, uncorrected_label
from spreadmap.surrogate.correction import applies as correction_applies

try:  # in place: every default of schemas/config.schema.yaml is filled here, so the rules read config plainly
    spreadmap_config.validate(config)
except spreadmap_config.ConfigError as error:
    raise WorkflowError(f"spreadmap: bad configuration: {error}") from None

RETRIES = 1  # a crash or a timeout is tried once more, then recorded as failed (a refusal: at once)
QUICK_FIRST = 10**8  # scheduling priority of the per-case jobs that take a second (render, metrics); above any run's
# the map model and what reads it (maps, decide, explorer, predict) before the surrogate's validation, which
# nothing of theirs waits for (run beside them with --cores 2; after them with --cores 1)
ANALYSES_FIRST = 10
CASES = {}  # case id -> scene parameters of the YADE script
CASE_OF = {}  # (rounded design point, preset, seed) -> case id under this config (the content is derived once)
SETS = {}  # set name ("lds", "lattice", "points", "fidelity", "knobs") -> list of (case id, label)
RANGES = config.get("ranges")  # optional: without it, the design space of spreadmap.design
SCENE_SHA256 = template_sha256()
SWEEPS = config.get("sweeps") or {}  # optional: no fixed sweeps, no LDS sequence to start the main job from
# the floor the cases are spread on and the powder model (dry or adhesive), named on every map,
# table and report
FLOOR = f"{floor_label(config)}; {powder_label(config)}"
# what the map model's numbers are: the floor, and the preset's step to `reference` when config
# `fidelity_correction` gives one (spreadmap.surrogate.correction); named on every map and decision
_CORRECTION = Correction.from_config(config)
_BASIS = _CORRECTION.label() if _CORRECTION else uncorrected_label(config["preset"], why=correction_applies(config))
MAP_BASIS = f"{FLOOR}; {_BASIS}"


def add_case(point, preset=None, seed=None):
    """The case id of a design point at a preset and packing seed (its content key included)."""
    preset = preset or config["preset"]
    seed = config["scene"]["seed"] if seed is None else seed
    asked = (tuple(rounded(point).values()), preset, int(seed))
    if asked not in CASE_OF:
        try:
            cid, params = case_scene(point, preset, config, seed, SCENE_SHA256)
        except (UnsafeTimeStep, ValueError) as error:
            raise WorkflowError(f"spreadmap: case refused before anything ran: {error}") from None
        CASES.setdefault(cid, params)
        CASE_OF[asked] = cid
    return CASE_OF[asked]


def case_cost_priority(wildcards):
    """Scheduling priority of a case's YADE run: its planned work (spheres x planned steps, in
    10^4), so that the costliest cases start first (longest-processing-time order) and a few
    slow cases do not run alone at the end of a sweep or a batch while the other cores idle."""
    scene = CASES[wildcards.case]
    return 1 + int(scene["n_particles"] * scene["estimated_steps"] / 1e4)


def register(set_name, point, label, preset=None, seed=None):
    """Add a design point to a set of cases (a set has a results table)."""
    SETS.setdefault(set_name, []).append((add_case(point, preset, seed), {"sweep": set_name, **label}))


def lds_size():
    return max(SWEEPS["lds"]["partitions"])


def lds_case_ids(n):
    """Case ids of the first n points of the LDS sequence (for `snakemake converge`)."""
    if n > len(LDS_SEQUENCE):
        raise WorkflowError(f"spreadmap: {n} LDS cases asked for, beyond converge.budget = {len(LDS_SEQUENCE)}")
    return LDS_SEQUENCE[:n]


_legacy = legacy_case_folders("results/cases")
if _legacy:  # results of a run before content keys: not re-used until migrated (never deleted)
    print(f"spreadmap: {len(_legacy)} case folders in results/cases/ have ids without a content key (before "
          f"issue 35; e.g. {_legacy[0].name}); `python tools/migrate_case_ids.py .` renames those it can key "
          f"so that they are re-used", file=sys.stderr)

try:
    _planned = list(planned_cases(config, lds_points=config["converge"]["budget"],
                                  scene_sha256=SCENE_SHA256))
except (UnsafeTimeStep, ValueError) as error:
    raise WorkflowError(f"spreadmap: case refused before anything ran: {error}") from None
LDS_SEQUENCE = []  # case ids of the LDS sequence up to the larger of the sweep and the converge budget
for _case in _planned:
    if _case.sweep == "lds":
        LDS_SEQUENCE.append(add_case(_case.point, preset=_case.preset))
    if _case.in_sweep:
        register(_case.sweep, _case.point, _case.label, preset=_case.preset)
        if _case.sweep == "lattice":  # one lattice size alone: results/tables/lattice_k3.csv runs k = 3 first
            register(f"lattice_k{_case.label['k']}", _case.point, _case.label, preset=_case.preset)
try:
    _points = chosen_points(config.get("points"), workflow.basedir, presets=config["presets"])  # points: optional
except ValueError as error:
    raise WorkflowError(f"spreadmap: bad chosen points: {error}") from None
for _i, _p in enumerate(_points):
    register("points", _p["point"], {"index": _i, "name": _p["name"]},
             preset=_p["preset"] or config["points"].get("preset"), seed=_p["seed"])  # None: the config's preset

# The fidelity study (`snakemake fidelity`): its own two sets, outside the main job. A knob value
# is a preset of its own (spreadmap.fidelity.plan), added to the presets here.
FIDELITY_SETS = ("fidelity", "knobs")
FIDELITY = config.get("fidelity") or {}  # optional: the fidelity study needs its section
KNOBS = FIDELITY.get("knobs") or {}
if config.get("fidelity"):
    config["presets"].update(knob_presets(config))
    for _i, _row in enumerate(preset_cases(config)):
        register("fidelity", _row["point"], {"index": _i, "name": _row["name"]}, preset=_row["preset"], seed=_row["seed"])
    for _i, _row in enumerate(knob_cases(config)):
        register("knobs", _row["point"], {"index": _i, "name": _row["name"], "knob": _row["knob"], "value": _row["value"],
                                          "is_base": _row["is_base"]}, preset=_row["preset"], seed=_row["seed"])


GROW = config["converge"]
STUDY_RULE = config["study_rule"]  # the study's five-statistic stopping test; GROW is the main job's loop (config converge)


# `snakemake converge` (rules/converge.smk): following its checkpoints
def converge_chain(n):
    """(case ids of the run's first n cases, the step before n or None), following the steps."""
    start = GROW["start"]
    ids, m, prev = list(lds_case_ids(start)), start, None  # refuses first without an LDS sweep
    preset = SWEEPS["lds"].get("preset")  # None: the config's preset
    while m < n:
        with open(checkpoints.converge_step.get(n=m).output.step) as fh:
            step = json.load(fh)
        if step["stop"] or step["next_n"] is None:
            raise WorkflowError(f"spreadmap: converge step {m} stopped ({step['reason']}); no step {n}")
        ids += [add_case(point, preset=preset) for point in step["next_batch"]]
        prev, m = m, step["next_n"]
    if m != n:
        raise WorkflowError(f"spreadmap: no converge step at {n} cases (the steps run {start}, ..., {m})")
    return ids, prev


def converge_step_input(wildcards):
    ids, prev = converge_chain(int(wildcards.n))
    out = {"metrics": [f"results/cases/{cid}/metrics.json" for cid in ids]}
    if prev is not None:
        out["previous"] = f"results/converge/step_{prev}.json"
    return out


def converge_final_step(wildcards):
    """Follow the converge checkpoints from the LDS start to the step that stopped."""
    n = GROW["start"]
    while True:
        with open(checkpoints.converge_step.get(n=n).output.step) as fh:
            step = json.load(fh)
        if step["stop"]:
            return f"results/converge/step_{n}.json"
        n = step["next_n"]


def converge_final_cases():
    """(case id, label in the converge table) of the whole converge run, in run order; the label
    (spreadmap.sweeps.loop_labels) holds the batch each came in and whether it is an LDS case
    (the start and each batch's LDS share) or an active one."""
    final = converge_final_step(None)
    n = int(final.rsplit("_", 1)[1].split(".")[0])
    ids, _ = converge_chain(n)
    with open(final) as fh:
        is_lds = json.load(fh)["is_lds"]
    return list(zip(ids, loop_labels(is_lds[:len(ids)], GROW["start"], GROW["batch"])))


def case_raw_input(wildcards):
    """The raw YADE record a case's metrics are computed from; none for a case restored from a
    published cases table (tools/restore_study.py: its metrics.json and benchmark are the published
    row, its raw record was not kept), so that a resumed run does not re-simulate it."""
    folder = f"results/cases/{wildcards.case}"
    if os.path.exists(f"{folder}/restored.json") and os.path.exists(f"{folder}/metrics.json"):
        return {}
    return {"raw": f"{folder}/raw.json"}


def case_files(set_name, filename):
    return [f"results/cases/{cid}/{filename}" for cid, _ in SETS.get(set_name, [])]


def prediction_targets():
    """The surrogate's predictions at the chosen points: asked for only when there are points."""
    return ["results/surrogate/predictions.csv"] if _points else []


def fidelity_outputs(wildcards):
    """Everything `snakemake fidelity` makes; a clear error without a `fidelity:` section."""
    if not FIDELITY:
        raise WorkflowError("spreadmap: `snakemake fidelity` needs a `fidelity:` section in the config "
                            "(points, presets, seeds, reference; see the shipped config.yaml)")
    return list(rules.fidelity_analysis.output)


# The main job's cases: the converge run (LDS start, then batches), the table the surrogate and
# the maps are trained on; and the chosen points.
TRAINING_TABLE = "results/converge/table.csv"


def main_tables():
    """The results tables of the main job: the converge run's and the chosen points' (if any)."""
    return [TRAINING_TABLE] + (["results/tables/points.csv"] if "points" in SETS else [])


wildcard_constraints:
    case=CASE_ID_PATTERN,
    set="[a-z][a-z0-9_]*",


def run_cores(wildcards):
    """The cores the run was given (--cores); None without them (a cluster profile): the timeline
    then counts the most jobs that ran at once."""
    try:
        return workflow.cores
    except WorkflowError:
        return None
