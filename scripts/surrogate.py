"""Snakemake entry: train, validate and save the MLP surrogates; figures and metrics table."""
from pathlib import Path

import pandas as pd

from spreadmap.surrogate import fit_surrogate, save_model
from spreadmap.surrogate_plots import plot_all
from spreadmap.logs import log_to

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
table = pd.read_csv(sm.input.table)
result = fit_surrogate(table, sm.params.surrogate, source_path=sm.input.table)
save_model(result.model, sm.output.model)
plot_all(result, Path(sm.output.model).parent, prefix="surrogate")
print(pd.read_csv(sm.output.metrics).to_string())
