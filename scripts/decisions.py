"""Snakemake entry: recommended settings per powder (table) and the probability maps (figure)."""
import pandas as pd

from spreadmap.decisions import decision_config, powders_from_config, recommendations
from spreadmap.decisions.figure import decision_figure
from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.surrogate import load_model
from spreadmap.surrogate.settings import map_config

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
dec = decision_config(sm.params.decisions)
support = map_config({"support": sm.params.support})["support"]
model = load_model(sm.input.model)
table, grids = recommendations(model, dec, support)
decision_figure(grids, table, powders_from_config(dec), dec, support, sm.output.figure, sm.params.floor)
write_text_atomically(sm.output.table, table.assign(floor=sm.params.floor).to_csv(index=False))
for powder, rows in table.groupby("powder", sort=False):
    print(f"{powder}:")
    for note in rows["note"]:
        print(f"  {note}")
with pd.option_context("display.width", 250, "display.max_columns", None):
    print(table.drop(columns="note").round(4).to_string())
