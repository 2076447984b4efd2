"""Snakemake entry: write a sweep's sample table (the same points the workflow registered)."""
import pandas as pd

from spreadmap.design import Design
from spreadmap.logs import log_to
from spreadmap.sampling import halton, lattice
from spreadmap.table import write_table

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
design = Design.from_ranges(sm.params.ranges)  # the design space (config ranges), built once
if "seed" in sm.params.keys():
    table = halton(sm.params.n, sm.params.seed, design)
else:
    table = pd.concat([lattice(k, design).assign(k=k) for k in sorted(set(sm.params.k))], ignore_index=True)
write_table(table, sm.output.samples)
