#!/usr/bin/env python
"""Predict MFR and PD, with the ensemble uncertainty, from a saved spreadmap surrogate.

    python scripts/predict.py MODEL.joblib --point f=0.3 d_um=30 h_um=60 v_mm_s=8 [--point ...]
    python scripts/predict.py MODEL.joblib --csv points.csv [--out predictions.csv]

Out-of-range points are predicted, flagged and warned about on stderr; malformed input exits with
status 2 and a message.  Under Snakemake's ``script:`` directive it reads ``snakemake.input``
(model, optional points CSV), ``snakemake.params`` (optional points) and writes
``snakemake.output[0]``.  All logic lives in spreadmap.surrogate (cli_main, snakemake_main).
"""
import sys

try:
    from spreadmap import surrogate
except ImportError:  # not installed: use the checkout (Snakemake copies scripts, so try the cwd too)
    import os
    from pathlib import Path

    sys.path[:0] = [str(Path(__file__).resolve().parents[1]), os.getcwd()]
    from spreadmap import surrogate

if "snakemake" in globals() and hasattr(globals()["snakemake"], "output"):
    surrogate.snakemake_main(globals()["snakemake"])
elif __name__ == "__main__":
    sys.exit(surrogate.cli_main())
