"""Snakemake entry: the MLP ensemble's machine map and powder map (a), beside the map model's, each
labelled with the MLP's validation against the noise (read from the validation table)."""
from pathlib import Path

import pandas as pd

from spreadmap import maps
from spreadmap.design import TARGETS, Design
from spreadmap.logs import log_to
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import read_table
from spreadmap.surrogate import load_model
from spreadmap.surrogate.settings import map_config
from spreadmap.table import usable_cases

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
p = sm.params
design = Design.from_ranges(p.ranges)
cfg = map_config(p.maps)
model = load_model(sm.input.model)
cases = case_noise(read_table(sm.input.table), p.noise_model, p.noise_calibration, p.counting_c)
usable = usable_cases(cases, [t for t in TARGETS if t in cases])
y, y_note, _ = maps.machine_y_axis(usable, model.targets, cfg["machine"]["y"])  # the map model's y (scripts/maps.py)
note = maps.validation_note(pd.read_csv(sm.input.validation), "mlp", ["mfr", y], n_cases=model.metadata["n_usable"],
                            other="gp")
print(note)
machine = {k: v for k, v in cfg["machine"].items() if k != "y"}
common = dict(y=y, ranges=design, support=cfg["support"], floor=p.floor, model_note=note)
maps.machine_map(model, Path(sm.output.machine_map).with_suffix(""), y_note=y_note, **machine, **common)
maps.powder_band_map(model, Path(sm.output.powder_band_map).with_suffix(""), **cfg["powder"], **common)
