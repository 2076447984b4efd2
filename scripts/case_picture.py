"""Snakemake entry: side and top views of one case at three moments."""
from spreadmap.case.pictures import plot_case_views
from spreadmap.logs import log_to
from spreadmap.records import read_raw

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
raw = read_raw(sm.input.raw)  # a damaged record is moved aside and re-made, never read
plot_case_views(raw, str(sm.output[0])[: -len(".png")], colour_by=sm.params.colour_by)
