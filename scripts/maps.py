"""Snakemake entry: design maps with their uncertainty, parallel coordinates, regimes, ranking."""
from pathlib import Path

import pandas as pd

from spreadmap import maps, sensitivity
from spreadmap.design import TARGETS, Design
from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import read_table
from spreadmap.surrogate import load_model
from spreadmap.surrogate.settings import map_config
from spreadmap.table import usable_cases

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
p = sm.params
design = Design.from_ranges(sm.params.ranges)  # the design space (config ranges), built once
cfg = map_config(p.maps)
out = Path(sm.output.ranking).parent
model = load_model(sm.input.model)
cases = case_noise(read_table(sm.input.table), p.noise_model, p.noise_calibration, p.counting_c)  # noise_model, noise_calibration
usable = usable_cases(cases, [t for t in TARGETS if t in cases])  # the usable cases with finite MFR and PD
y, y_note, scores = maps.machine_y_axis(usable, model.targets, cfg["machine"]["y"])
# each candidate's information beyond MFR and its r with MFR
write_text_atomically(sm.output.y_choice, scores.assign(floor=p.floor).to_csv(index=False))
if cfg["machine"]["y"] == "auto":
    print(f"machine map y axis: {y}" + (f" (scores beyond MFR:\n{scores.to_string()})" if len(scores) else
                                        " (no layer-quality target in the model)"))
machine = {k: v for k, v in cfg["machine"].items() if k != "y"}
support = cfg["support"]
floor = p.floor  # the floor the cases ran on, named on every map and in its CSV
maps.machine_map(model, out / "machine_map", y=y, ranges=design, support=support, y_note=y_note, floor=floor,
                 **machine)
maps.powder_band_map(model, out / "powder_band_map", y=y, ranges=design, support=support, floor=floor,
                     **cfg["powder"])
maps.powder_cluster_map(model, out / "powder_cluster_map", y=y, ranges=design, support=support, floor=floor,
                        **cfg["powder"])
maps.parallel_coordinates(cases, out / "parallel_coordinates", mfr_min=cfg["best_mfr_min"], ranges=design,
                          floor=floor)
maps.regime_overlay(cases, model, out / "regime_overlay", p.regime, ranges=design, support=support, floor=floor,
                    **cfg["regime_plane"])
ranking = sensitivity.sensitivity(model, list(model.targets), n=cfg["sobol_n"], draws=cfg["sobol_draws"],
                                  ranges=design)
write_text_atomically(sm.output.ranking, ranking.assign(floor=floor).to_csv(index=False))
sensitivity.plot_ranking(ranking, out / "sensitivity_ranking", floor)
with pd.option_context("display.width", 250, "display.max_columns", None):
    print(ranking.round(3).to_string())
