# Parse-time set-up: validate the configuration and register every case the targets can ask for.
# Per-case values reach the jobs as params from this registry (never through a shared table file,
# which would re-run every case whenever the table grows).
from spreadmap import config as spreadmap_config
from spreadmap.cases import CASE_ID_PATTERN, case_id, rounded
from spreadmap.scene import UnsafeTimeStep, scene_parameters

try:
    spreadmap_config.validate(config)
except spreadmap_config.ConfigError as error:
    raise WorkflowError(f"spreadmap: bad configuration: {error}") from None

RETRIES = 1  # a case that produced nothing (crash, timeout) is tried once more, then recorded as failed
CASES = {}  # case id -> scene parameters of the YADE script
SETS = {}  # set name (sweep, "cases", ...) -> list of (case id, label)


def register(set_name, point, preset=None, seed=None, **label):
    """Add a design point to a set of cases; the same content is one case whatever the set."""
    preset = preset or config["preset"]
    seed = config["scene"]["seed"] if seed is None else seed
    cid = case_id(point, preset, seed)
    if cid not in CASES:
        try:
            CASES[cid] = scene_parameters(rounded(point), preset, config, cid, seed)
        except (UnsafeTimeStep, ValueError) as error:
            raise WorkflowError(f"spreadmap: case refused before anything ran: {error}") from None
    SETS.setdefault(set_name, []).append((cid, {"sweep": set_name, "index": len(SETS.get(set_name, [])), **label}))
    return cid


for _i, (_name, _case) in enumerate((config.get("cases") or {}).items()):
    register("cases", _case, preset=_case.get("preset"), name=_name)


def case_files(set_name, filename):
    return [f"results/cases/{cid}/{filename}" for cid, _ in SETS.get(set_name, [])]


wildcard_constraints:
    case=CASE_ID_PATTERN,
