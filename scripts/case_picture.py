"""Snakemake entry: side and top views of one case at three moments."""
import json

from spreadmap.trajectory import plot_case_views
from spreadmap.logs import log_to

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
with open(sm.input.raw) as fh:
    raw = json.load(fh)
plot_case_views(raw, str(sm.output[0])[: -len(".png")], colour_by=sm.params.colour_by)
