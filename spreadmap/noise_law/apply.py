"""The fitted noise law applied to a results table: each case's MFR and PD noise SD from the law
(config `noise_model`) in place of the counting law's stated SD, the layer measures' SDs scaled by
the hand bands (config `noise_calibration`) as before.

Config section (coefficients from tools/fit_noise_model.py, docs/noise):

    noise_model:
      n_ref: 150            # the law's reference count and h/d
      h_over_d_ref: 2.0
      mfr: {rel_sd: ..., n_exponent: ..., h_over_d_exponent: ...}
      pd: {rel_sd: ..., n_exponent: ..., h_over_d_exponent: ...}

SD = value x rel_sd x (N / n_ref)^n_exponent x ((h/d) / h_over_d_ref)^h_over_d_exponent, with N the
count the case's own counting law used (`n_passed` for MFR, `n_pd` for PD). Below one sphere's
worth (a jammed case, an empty box) the SD is the law's at N = 1 in units of one sphere's worth of
the measure, as the counting law's floor (spreadmap.metrics.noise.counting_sd) is.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .. import targets as registry
from ..config import NOISE_LAW_TARGETS, check_sections
from ..design import h_over_d
from ..metrics.noise import calibrated_noise
from ..schema import checked, section_schema

# the count behind each target's counting law (spreadmap.metrics.case)
COUNT = {name: registry.REGISTRY[name].count_column for name in NOISE_LAW_TARGETS}  # mfr, pd
MODEL_TARGETS = NOISE_LAW_TARGETS  # mfr, pd
# the schema's defaults, for callers without a config: metrics.counting_noise_c, and the law's
# reference count and h/d (noise_model.n_ref, h_over_d_ref) for a law handed without them
COUNTING_NOISE_C = checked("metrics")["counting_noise_c"]
LAW_REFS = {key: section_schema("noise_model")["properties"][key]["default"] for key in ("n_ref", "h_over_d_ref")}


def law_rel_sd(n: np.ndarray, h_over_d: np.ndarray, law: dict, n_ref: float, hd_ref: float) -> np.ndarray:
    """The law's relative SD at count n and h/d."""
    return law["rel_sd"] * (n / n_ref) ** law["n_exponent"] * (h_over_d / hd_ref) ** law["h_over_d_exponent"]


def modelled_sd(table: pd.DataFrame, target: str, noise_model: dict, counting_c: float) -> np.ndarray:
    """Per row, the law's noise SD of `target` (NaN where the case has no value). `counting_c` is
    the c the table's stated SDs were computed with; it is used only where a case's value or count
    is 0, to read one sphere's worth of the measure off its stated SD."""
    law = noise_model[target]
    value = pd.to_numeric(table[target], errors="coerce").to_numpy(float)
    stated = pd.to_numeric(table[f"{target}_sd"], errors="coerce").to_numpy(float)
    count_col = COUNT[target]
    if count_col not in table:
        raise ValueError(f"noise_model: the table has no `{count_col}` column (the count behind {target}'s noise)")
    n = pd.to_numeric(table[count_col], errors="coerce").to_numpy(float)
    ratio = h_over_d(table)
    n_eff = np.maximum(n, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        per_sphere = np.where((n > 0) & (value > 0), value / n, stated / (counting_c * np.sqrt(n_eff)))
    refs = {**LAW_REFS, **noise_model}
    rel = law_rel_sd(n_eff, ratio, law, float(refs["n_ref"]), float(refs["h_over_d_ref"]))
    return np.abs(per_sphere) * n_eff * rel


def case_noise(table: pd.DataFrame, noise_model: dict | None, noise_calibration: list | None,
               counting_c: float = COUNTING_NOISE_C) -> pd.DataFrame:
    """A copy of a results table whose noise SDs are those every analysis should weigh the cases by.

    MFR's and PD's from the fitted law where `noise_model` gives one, the others (and all of them
    without a law) the stated SDs scaled by `noise_calibration`'s bands. The values are left as
    they are.

    Parameters
    ----------
    table : pandas.DataFrame
        A results table: the targets, their stated SDs (``targets.sd_columns()``), ``h_um``, ``d_um``
        and, for a target the law sets, the count behind its noise (``n_passed`` for MFR,
        ``n_pd`` for PD).
    noise_model : dict or None
        The config's `noise_model` section (the module docstring); None or empty: no law.
    noise_calibration : list or None
        The config's `noise_calibration` regions (``spreadmap.metrics.noise.calibration_factors``).
    counting_c : float, optional
        The counting law's constant c (dimensionless) the table's stated SDs were computed with;
        used only where a case's value or count is 0, to read one sphere's worth of the measure
        off its stated SD.

    Returns
    -------
    pandas.DataFrame
        A copy of `table` with the noise SD columns replaced, in the targets' units.

    Raises
    ------
    ValueError
        If the sections clash (``check_sections``) or the table lacks the count column a law
        needs.
    """
    check_sections(noise_model, noise_calibration)
    out = calibrated_noise(table, noise_calibration)
    for target in MODEL_TARGETS:
        if noise_model and target in noise_model and f"{target}_sd" in out and not out.empty:
            out[f"{target}_sd"] = modelled_sd(out, target, noise_model, counting_c)
    return out
