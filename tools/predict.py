#!/usr/bin/env python
"""Predict with a saved spreadmap surrogate: per target the mean, the model's SD and the SD a new
DEM run would show there (model and noise).

    .venv/bin/python tools/predict.py MODEL.joblib --point f=0.3 d_um=30 h_um=60 v_mm_s=8 [--point ...]
    .venv/bin/python tools/predict.py MODEL.joblib --csv points.csv [--out predictions.csv]

The CSV may be in the README's points format (name, preset, seed beside f, d_um, h_um, v_mm_s).
Points outside the design ranges, far from the data, or with a gap below one particle are
predicted and warned about on stderr; physically meaningless values, malformed input and a model
file that is not a surrogate exit with status 2 and a one-line message. The logic lives in
spreadmap.surrogate.cli; the workflow's rule predict runs it through scripts/predict.py.
"""
import sys

from spreadmap.surrogate.cli import cli_main

if __name__ == "__main__":
    sys.exit(cli_main())
