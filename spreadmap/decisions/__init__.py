"""From the maps to a decision: which settings to run a powder at, and how sure that is.

``config_section`` reads the ``decisions:`` config section (defaults from the schema) and checks it;
``feasibility`` computes, from the surrogate's joint posterior draws, the probability that every
bound is met over the machine's (h, v) grid per powder, and picks the fastest and the best-quality
setting; ``figure`` draws that probability with the recommended points; ``explorer`` writes the
self-contained HTML page to explore the 4-D map by hand.
"""
from .config_section import DecisionError, decision_config
from .feasibility import Powder, feasibility, powders_from_config, recommend, recommendations

__all__ = ["DecisionError", "Powder", "decision_config", "feasibility", "powders_from_config", "recommend",
           "recommendations"]
