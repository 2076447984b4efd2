"""Snakemake entry: the surrogate's validation (repeated k-fold of the GP and the bootstrap MLP
ensemble against the noise, the study's MLP protocol, the learning curve), its tables and figures.
Nothing of the maps waits for it (rule surrogate fits the map model on its own)."""
from pathlib import Path

import pandas as pd

from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import read_table
from spreadmap.surrogate import validate_surrogate
from spreadmap.surrogate.plots import plot_all

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
# the same table and noise SDs as the map model's (scripts/surrogate.py)
table = case_noise(read_table(sm.input.table), sm.params.noise_model, sm.params.noise_calibration, sm.params.counting_c)
result = validate_surrogate(table, sm.params.surrogate, n_jobs=sm.threads)  # a process per core the rule was given
out = Path(sm.output.metrics).parent
out.mkdir(parents=True, exist_ok=True)
write_text_atomically(sm.output.metrics, result.validation.to_csv(index=False))  # what the figures draw, as numbers
write_text_atomically(sm.output.study_runs, result.study_runs.to_csv(index=False))
plot_all(result, out, prefix="surrogate", floor=sm.params.floor)
for note in result.notes:
    print(note)
with pd.option_context("display.width", 250, "display.max_columns", None):
    print(result.validation.round(4).to_string())
    print(result.study_summary.round(4).to_string())
