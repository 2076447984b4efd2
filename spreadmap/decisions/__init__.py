"""From the maps to a decision: which settings to run a powder at, and how sure that is.

``config_section`` reads the ``decisions:`` config section (defaults from the schema) and checks it;
``feasibility`` computes, from the surrogate's joint posterior draws, the probability that every
bound is met over the machine's (h, v) grid per powder, and picks the fastest and the best-quality
setting; ``figure`` draws that probability with the recommended points; ``explorer`` writes the
self-contained HTML page to explore the 4-D map by hand.
"""
import importlib

from .config_section import DecisionError, decision_config

# The feasibility names are loaded when first used: the config's checks (wired in by spreadmap/__init__) import
# config_section on every Snakemake start, and feasibility imports the maps, matplotlib and
# scipy.stats (0.8 s a process).
# (``spreadmap.decisions.feasibility`` is the module; its function of that name is
# ``spreadmap.decisions.feasibility.feasibility``.)
_FEASIBILITY = ("Powder", "powders_from_config", "recommend", "recommendations")


def __getattr__(name: str):
    if name in _FEASIBILITY:
        return getattr(importlib.import_module(f"{__name__}.feasibility"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["DecisionError", "Powder", "decision_config", "powders_from_config", "recommend", "recommendations"]
