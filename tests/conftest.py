"""Shared fixtures. Tests marked `yade` run Debian's real `yade` binary on small scenes; they fail
(never skip) when it is missing: `bash tools/setup.sh` installs it."""
from __future__ import annotations

import copy
import json
import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from spreadmap import config as spreadmap_config
from spreadmap.cases import case_id, rounded
from spreadmap.launcher import run_case
from spreadmap.render import render, write_atomically
from spreadmap.scene import scene_parameters

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def config() -> dict:
    return spreadmap_config.load(ROOT / "config.yaml")


def run_scene(params: dict, workdir: Path) -> tuple[dict, dict]:
    """Render and run one case in workdir; returns (launcher result, raw record or {})."""
    script = workdir / "case.py"
    write_atomically(script, render(params))
    result = run_case(script, workdir / "raw.json", workdir / "run.log", params["timeout_s"])
    raw = json.loads((workdir / "raw.json").read_text()) if (workdir / "raw.json").exists() else {}
    return result, raw


def case_params(config: dict, point: dict, preset: str = "smoke", **overrides) -> dict:
    cid = case_id(point, preset, config["scene"]["seed"])
    params = scene_parameters(rounded(point), preset, config, cid)
    params.update(overrides)
    return params


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
