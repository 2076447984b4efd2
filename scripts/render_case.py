"""Snakemake entry: write one case's YADE script (parameters embedded)."""
from spreadmap.render import render, write_atomically
from spreadmap.logs import log_to

log_to(snakemake)  # noqa: F821

write_atomically(snakemake.output.script, render(snakemake.params.scene))  # noqa: F821
