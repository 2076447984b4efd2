"""Snakemake entry: write one case's YADE script (parameters embedded)."""
from spreadmap.render import render, write_atomically

write_atomically(snakemake.output.script, render(snakemake.params.scene))  # noqa: F821
