"""Snakemake entry: write one case's YADE script (parameters embedded)."""
from spreadmap.case.render import render
from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to

log_to(snakemake)  # noqa: F821

write_text_atomically(snakemake.output.script, render(snakemake.params.scene.params))  # noqa: F821
