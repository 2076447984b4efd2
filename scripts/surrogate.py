"""Snakemake entry: the map model (each target's final model on every usable case), saved; its
validation is rule surrogate_validation's (scripts/surrogate_validation.py), which nothing of the
maps waits for. With `surrogate.model: best` the model is chosen by that validation, read back here.
Rule surrogate_mlp gives params `model_kind` (mlp): that model for every target, whatever
`surrogate.model` says (the MLP's maps beside the map model's)."""
import pandas as pd

from spreadmap.design import Design
from spreadmap.logs import log_to
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import read_table
from spreadmap.surrogate import fit_map_model, save_model
from spreadmap.surrogate.correction import Correction

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
design = Design.from_ranges(sm.params.ranges)  # the design space (config ranges), built once
# the cases' noise SDs: MFR's and PD's from the fitted law (config noise_model), the others scaled by
# region (config noise_calibration); the table keeps the stated ones
table = case_noise(read_table(sm.input.table), sm.params.noise_model, sm.params.noise_calibration, sm.params.counting_c)
# only `best` needs the validation's choice (the rule asks for surrogate_metrics.csv then)
validation = getattr(sm.input, "validation", None)
validation = pd.read_csv(validation) if validation else None
kind = getattr(sm.params, "model_kind", None)
surrogate = sm.params.surrogate if kind is None else {**sm.params.surrogate, "model": kind}
model = fit_map_model(table, surrogate, source_path=sm.input.table, ranges=design, validation=validation)
# the map model's numbers as `reference` would read them, where config fidelity_correction gives a
# factor (the validation and its figures stay against the cases' own preset)
# (the rule passes it only where it applies to this run's preset and floor: rules/common.smk)
correction = Correction.from_config({"fidelity_correction": sm.params.correction})
if correction is not None:
    correction.attach(model)
    print(f"map model's means: {correction.label(model.targets)}")
save_model(model, sm.output.model)
