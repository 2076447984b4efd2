"""The report's captions (rules/captions/*.rst), rendered as Snakemake renders them (Jinja2 with
the config as snakemake.config): every key they name exists, and the values they state come from
the config, not from numbers typed into the text."""
import copy
import re
from types import SimpleNamespace

import pytest
from conftest import ROOT
from jinja2 import Environment, StrictUndefined

CAPTIONS = sorted((ROOT / "rules" / "captions").glob("*.rst"))
SURROGATE = {"parity", "r2_vs_neurons", "learning_curve"}  # the surrogate's own captions: tested with it
# numbers that are the code's, not the config's: 4-D (the design space), 2 standard errors (the
# fidelity study's resolution), 95 % (the bootstrap intervals of the Sobol indices)
# numbers that are method, written in the code, not settings: a ratio's threshold 1, the contour
# levels of the regime probabilities, the 95 % draws' intervals and the 97.5 % ordering rule
FIXED = {"sampling_study": {"4"}, "fidelity_pareto": {"2"}, "sensitivity_ranking": {"95", "97.5"},
         "converge_path": {"1"}, "regime_overlay": {"0.1", "0.5", "0.9"}, "powder_band_map": {"0", "95"}}


def render(path, config):
    env = Environment(trim_blocks=True, lstrip_blocks=True, undefined=StrictUndefined)
    return env.from_string(path.read_text()).render(snakemake=SimpleNamespace(config=config))


def test_the_captions_are_found():
    assert {p.stem for p in CAPTIONS} >= {"statistics", "distributions", "regime_overlay", "fidelity_pareto"}


@pytest.mark.parametrize("path", CAPTIONS, ids=lambda p: p.stem)
def test_every_caption_renders_with_the_shipped_config(path, config):
    text = render(path, config)
    assert text.strip() and "{{" not in text and "{%" not in text


@pytest.mark.parametrize("path", [p for p in CAPTIONS if p.stem not in SURROGATE], ids=lambda p: p.stem)
def test_no_caption_types_a_number_the_config_holds(path):
    text = re.sub(r"\{\{.*?\}\}|\{%.*?%\}", " ", path.read_text())
    numbers = set(re.findall(r"\d+(?:\.\d+)?", text))
    assert numbers <= FIXED.get(path.stem, set()), f"{path.name}: {sorted(numbers)} typed in, not from the config"


def test_captions_follow_the_config(config):
    cfg = copy.deepcopy(config)
    cfg["sweeps"]["lds"]["preset"] = "fast"  # a sweep at its own preset
    cfg["regime"].update(short_feed_coverage_min=0.123, short_feed_thickness_min=0.456)
    cfg["study_rule"]["tolerance"] = 0.02
    for name in ("statistics", "distributions"):
        text = render(ROOT / "rules" / "captions" / f"{name}.rst", cfg)
        assert f"lds fast, lattice {cfg['preset']}" in text, text
    assert "±2.0 %" in render(ROOT / "rules" / "captions" / "statistics.rst", cfg)
    regime = render(ROOT / "rules" / "captions" / "regime_overlay.rst", cfg)
    assert "0.123" in regime and "0.456" in regime
