"""Snakemake entry: the surrogate's predictions at the chosen points (spreadmap.surrogate.cli; the
same from the command line: tools/predict.py)."""
from spreadmap.surrogate import cli

cli.snakemake_main(snakemake)  # noqa: F821
