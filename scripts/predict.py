#!/usr/bin/env python
"""Predict with a saved spreadmap surrogate: per target the mean, the model's SD and the SD a new
DEM run would show there (model and noise).

    python scripts/predict.py MODEL.joblib --point f=0.3 d_um=30 h_um=60 v_mm_s=8 [--point ...]
    python scripts/predict.py MODEL.joblib --csv points.csv [--out predictions.csv]

The CSV may be in the README's points format (name, preset, seed beside f, d_um, h_um, v_mm_s).
Points outside the design ranges, far from the data, or with a gap below one particle are
predicted and warned about on stderr; physically meaningless values, malformed input and a model
file that is not a surrogate exit with status 2 and a one-line message. Under Snakemake's
``script:`` directive it reads ``snakemake.input`` (model, optional points CSV),
``snakemake.params`` (optional points) and writes ``snakemake.output[0]``. The logic lives in
spreadmap.surrogate.cli.
"""
import sys

try:
    from spreadmap.surrogate import cli
except ImportError:  # not installed: use the checkout (Snakemake copies scripts, so try the cwd too)
    import os
    from pathlib import Path

    sys.path[:0] = [str(Path(__file__).resolve().parents[1]), os.getcwd()]
    from spreadmap.surrogate import cli

if "snakemake" in globals() and hasattr(globals()["snakemake"], "output"):
    cli.snakemake_main(globals()["snakemake"])
elif __name__ == "__main__":
    sys.exit(cli.cli_main())
