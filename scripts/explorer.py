"""Snakemake entry: the explorer page (one self-contained HTML file) and its numbers as CSV."""
from spreadmap.decisions import decision_config
from spreadmap.decisions.explorer import write_explorer
from spreadmap.logs import log_to
from spreadmap.surrogate import load_model
from spreadmap.surrogate.settings import map_config

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
dec = decision_config(sm.params.decisions)
support = map_config({"support": sm.params.support})["support"]
model = load_model(sm.input.model)
data = write_explorer(model, dec, support, sm.output.html, sm.output.csv, floor=sm.params.floor)
print(f"explorer: {len(data['f'])} x {len(data['d'])} slider positions (f, d), {len(data['h'])} x {len(data['v'])} "
      f"(h, v) cells, {len(data['targets'])} targets, {len(model.train_X)} cases -> {sm.output.html}")
