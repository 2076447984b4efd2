"""Snakemake entry: legacy VTK files (ParaView) of one case's snapshots."""
from spreadmap.case.vtk_export import export_case
from spreadmap.logs import log_to
from spreadmap.records import read_raw

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
raw = read_raw(sm.input.raw)  # a damaged record is moved aside and re-made, never read
for path in export_case(raw, sm.output[0]):
    print(path)
