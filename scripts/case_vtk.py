"""Snakemake entry: legacy VTK files (ParaView) of one case's snapshots."""
import json

from spreadmap.vtk_export import export_case
from spreadmap.logs import log_to

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
with open(sm.input.raw) as fh:
    raw = json.load(fh)
for path in export_case(raw, sm.output[0]):
    print(path)
