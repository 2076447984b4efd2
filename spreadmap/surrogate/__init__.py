"""The noise-aware surrogate of the DEM results, its validation, the saved model and prediction.

Submodules, one job each: ``settings`` (config, no scikit-learn), ``training_rows`` (usable cases,
partitions, per-case noise), ``features`` (model inputs), ``noise_sd`` (a new run's noise SD),
``models`` (GP and MLP ensemble), ``validation`` (repeated k-fold numbers), ``study_protocol`` (the
reference study's protocol), ``fitting`` (all of it on a table: the map model and its validation,
apart or together), ``saved_model`` (file and loading), ``prediction`` (points in, mean and SDs
out), ``cli`` (tools/predict.py, scripts/predict.py), ``plots``, ``correction`` (the
preset-to-reference factor on the maps).

Importing this package imports no scikit-learn: the package wires ``settings.problems`` into the
config's validation (spreadmap/__init__.py).
The other names below are loaded on first use.
"""
from __future__ import annotations

from importlib import import_module

from .settings import make_config

_LAZY = {
    "fit_surrogate": "fitting", "SurrogateResult": "fitting", "fit_map_model": "fitting",
    "validate_surrogate": "fitting", "SurrogateValidation": "fitting",
    "SurrogateModel": "saved_model", "ModelFileError": "saved_model", "load_model": "saved_model",
    "save_model": "saved_model", "sidecar_path": "saved_model",
    "predict": "prediction", "OutOfRangeWarning": "prediction", "as_points": "prediction",
    "cli_main": "cli", "snakemake_main": "cli",
}

__all__ = ["make_config", *_LAZY]


def __getattr__(name):
    if name in _LAZY:
        return getattr(import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
