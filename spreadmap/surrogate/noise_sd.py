"""The noise SD a new DEM run would show at a design point, from the cases' own noise estimates.

Each case's MFR and PD carry counting noise (relative SD ~0.45 / sqrt(N), N the spheres that pass),
so the noise SD varies over the design space. Where the table gives ``<target>_sd`` per case, ln SD
is fitted by least squares as a linear function of the standardised inputs (the counting law is a
power law of N, which is a smooth function of h/d and the window), and the fit gives the SD at a
new point. A fit of ln SD gives the geometric mean of the SDs, which for SDs that are themselves
estimates from few degrees of freedom (the layer measures' block jackknife, 2-7 blocks) is well
below their root mean square: with 2 degrees of freedom exp(E ln s) = 0.75 sigma. The fit's
variance is therefore rescaled by the mean of exp(2 residual) (Duan's smearing estimate), so that
the predicted variance is the mean of the cases' variances, not their geometric mean; for SDs
that follow the counting law closely (MFR, PD) the factor is ~1.
Without per-case SDs the noise is one constant, estimated by the model.
"""
from __future__ import annotations

import numpy as np


class CaseNoise:
    """ln sd = b0 + b . z(x), fitted on the cases that have a finite positive SD."""

    def fit(self, Z: np.ndarray, sd: np.ndarray) -> "CaseNoise":
        ok = np.isfinite(sd) & (sd > 0)
        if ok.sum() < 2:
            raise ValueError("per-case noise SD: fewer than two cases with a finite positive value")
        A = np.column_stack([np.ones(ok.sum()), Z[ok]])
        # a ridge-small penalty keeps the fit defined when there are fewer cases than inputs
        lam = 1e-6 * np.eye(A.shape[1])
        self.coef_ = np.linalg.solve(A.T @ A + lam, A.T @ np.log(sd[ok]))
        residual = np.log(sd[ok]) - A @ self.coef_
        self.smearing_ = float(np.sqrt(np.mean(np.exp(2.0 * residual))))
        self.n_ = int(ok.sum())
        return self

    def sd(self, Z: np.ndarray) -> np.ndarray:
        # models saved before the smearing factor load without it (factor 1)
        return getattr(self, "smearing_", 1.0) * np.exp(self.coef_[0] + Z @ self.coef_[1:])


def fill_missing(sd: np.ndarray | None) -> np.ndarray | None:
    """Per-case SDs with the missing or non-positive ones replaced by the median of the others."""
    if sd is None:
        return None
    sd = np.asarray(sd, float).copy()
    bad = ~(np.isfinite(sd) & (sd > 0))
    if bad.all():
        return None
    sd[bad] = np.median(sd[~bad])
    return sd
