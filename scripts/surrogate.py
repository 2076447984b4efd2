"""Snakemake entry: train and validate the surrogate, save it, draw its validation figures."""
from pathlib import Path

import pandas as pd

from spreadmap.design import Design
from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import read_table
from spreadmap.surrogate import fit_surrogate, save_model
from spreadmap.surrogate.correction import Correction
from spreadmap.surrogate.plots import plot_all

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
design = Design.from_ranges(sm.params.ranges)  # the design space (config ranges), built once
# the cases' noise SDs: MFR's and PD's from the fitted law (config noise_model), the others scaled by
# region (config noise_calibration); the table keeps the stated ones
table = case_noise(read_table(sm.input.table), sm.params.noise_model, sm.params.noise_calibration, sm.params.counting_c)
result = fit_surrogate(table, sm.params.surrogate, source_path=sm.input.table, ranges=design)
# the map model's numbers as `reference` would read them, where config fidelity_correction gives a
# factor (the validation above and its figures stay against the cases' own preset)
# (the rule passes it only where it applies to this run's preset and floor: rules/common.smk)
correction = Correction.from_config({"fidelity_correction": sm.params.correction})
if correction is not None:
    result.model.correction = correction
    result.model.metadata["fidelity_correction"] = {"label": correction.label(result.model.targets),
                                                    "factors": correction.factors, "source": correction.source}
    print(f"map model's means: {correction.label(result.model.targets)}")
save_model(result.model, sm.output.model)
out = Path(sm.output.model).parent
out.mkdir(parents=True, exist_ok=True)
write_text_atomically(sm.output.metrics, result.validation.to_csv(index=False))  # what the figures draw, as numbers
write_text_atomically(out / "surrogate_study_runs.csv", result.study_runs.to_csv(index=False))
plot_all(result, out, prefix="surrogate", floor=sm.params.floor)
with pd.option_context("display.width", 250, "display.max_columns", None):
    print(result.validation.round(4).to_string())
    print(result.study_summary.round(4).to_string())
