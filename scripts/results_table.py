"""Snakemake entry: one results table (CSV) from per-case metrics, with the sweep/index labels."""
from spreadmap.logs import log_to
from spreadmap.table import build_table, write_table

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
table = build_table(sm.input.metrics, sm.input.benchmarks, sm.params.labels)
write_table(table, sm.output.table)
