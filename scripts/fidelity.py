"""Snakemake entry: the fidelity study's tables, goal checks and figures from its two results tables."""
import json
from pathlib import Path

import pandas as pd

from spreadmap.fidelity import fidelity_plots, study
from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.records import read_table

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
reference = sm.params.reference
cases = read_table(sm.input.presets)  # a half-written table is moved aside and re-made, never read
per_point, presets = study.preset_errors(cases, reference)
knobs = study.knob_errors(read_table(sm.input.knobs)) if sm.input.get("knobs") else None
goals = [study.goal(presets, name) for name in sm.params.goal_presets if name in set(presets["preset"])]

write_text_atomically(sm.output.per_point, per_point.to_csv(index=False))
write_text_atomically(sm.output.presets, presets.to_csv(index=False))
write_text_atomically(sm.output.knobs, (knobs if knobs is not None else pd.DataFrame()).to_csv(index=False))
summary = {"reference": reference, "presets": presets.to_dict("records"), "goals": goals,
           "machine": study.machine_description(cases)}
write_text_atomically(sm.output.summary, json.dumps(summary, indent=1, default=float))
write_text_atomically(sm.output.markdown, study.markdown_summary(presets, per_point, knobs, reference, goals))
fidelity_plots.pareto_figure(presets, reference, Path(sm.output.pareto).with_suffix(""))
if knobs is not None:
    fidelity_plots.knobs_figure(knobs, sm.params.knob_preset, Path(sm.output.knobs_figure).with_suffix(""))
print(Path(sm.output.markdown).read_text())
