"""A two-level multi-fidelity model of one target: many cheap cases and a few expensive ones.

Kennedy & O'Hagan's autoregressive model (Biometrika 87 (2000) 1-13) in its recursive form (Le
Gratiet & Garnier, 2014): the expensive level is y_hi(x) = rho y_lo(x) + delta(x), with y_lo the
cheap level's GP and delta an independent GP (the discrepancy). Fitted in two steps on
``models.GPModel``, the product's noise-aware GP:
1. the cheap level's GP on the cheap cases (with their per-case noise SDs);
2. for a scale rho, the discrepancy's GP on the expensive cases' residuals y_hi - rho m_lo(x_hi),
   each with the noise of its run plus rho^2 times the cheap GP's variance at that point (what the
   cheap level does not know there); rho maximises the discrepancy GP's log marginal likelihood in
   the target's own units (the standardisation's Jacobian taken out), bounded scalar search.
Prediction: mean rho m_lo + m_delta, variance rho^2 s_lo^2 + s_delta^2 (independent levels); a new
expensive run's noise is the discrepancy model's per-case noise. The expensive cases need not be
nested in the cheap ones (the cheap GP's variance at them is carried).

Lab code until the maps use it (issue 64): it is one route to the truth level, to be compared with
a GP on the expensive cases alone and with a scaling rule of the cheap level on held-out cases.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar

from spreadmap.surrogate.models import GPModel


class AR1Model:
    """y_hi = rho y_lo + delta, each level a ``GPModel`` (``fit``, ``latent``, ``predictive``, ``draws``)."""

    kind = "ar1"

    def __init__(self, inputs: str = "physics", rho_bounds: tuple[float, float] = (0.2, 2.0), seed: int = 0):
        self.inputs, self.rho_bounds, self.seed = inputs, tuple(rho_bounds), int(seed)

    def _discrepancy(self, rho: float, X_hi, y_hi, sd_hi, m_lo, s_lo) -> GPModel:
        sd = np.sqrt(np.asarray(sd_hi, float) ** 2 + (rho * s_lo) ** 2)
        return GPModel(self.inputs, seed=self.seed).fit(X_hi, np.asarray(y_hi, float) - rho * m_lo, sd)

    @staticmethod
    def _log_likelihood(model: GPModel) -> float:
        """The GP's log marginal likelihood in the target's own units (GPModel standardises y)."""
        n = len(model.gp_.y_train_)
        return float(model.gp_.log_marginal_likelihood_value_) - n * math.log(model.y_sd_)

    def fit(self, X_lo, y_lo, sd_lo, X_hi, y_hi, sd_hi) -> "AR1Model":
        """Fit the cheap level on (X_lo, y_lo, sd_lo), then rho and the discrepancy on the expensive
        cases (X_hi, y_hi, sd_hi); SDs are each case's noise SD (None: the GP's white noise alone)."""
        X_hi = np.asarray(X_hi, float)
        if len(X_hi) < 3:
            raise ValueError(f"an AR(1) model needs at least 3 expensive cases, got {len(X_hi)}")
        self.lo_ = GPModel(self.inputs, seed=self.seed).fit(X_lo, y_lo, sd_lo)
        m_lo, s_lo = self.lo_.latent(X_hi)
        sd_hi = np.zeros(len(X_hi)) if sd_hi is None else np.asarray(sd_hi, float)
        best = minimize_scalar(lambda r: -self._log_likelihood(self._discrepancy(r, X_hi, y_hi, sd_hi, m_lo, s_lo)),
                               bounds=self.rho_bounds, method="bounded", options={"xatol": 1e-3})
        self.rho_ = float(best.x)
        self.delta_ = self._discrepancy(self.rho_, X_hi, y_hi, sd_hi, m_lo, s_lo)
        return self

    def latent(self, X):
        """The expensive level's mean function and its SD at X."""
        m_lo, s_lo = self.lo_.latent(X)
        m_d, s_d = self.delta_.latent(X)
        return self.rho_ * m_lo + m_d, np.sqrt((self.rho_ * s_lo) ** 2 + s_d ** 2)

    def noise_sd(self, X) -> np.ndarray:
        """The SD of one new expensive run about the mean function (the discrepancy's noise model)."""
        return self.delta_.noise_sd(X)

    def predictive(self, X):
        """Mean, model SD and the SD of a new expensive run (model and noise) at X."""
        mean, msd = self.latent(X)
        return mean, msd, np.sqrt(msd ** 2 + self.noise_sd(X) ** 2)

    def draws(self, X, n: int, rng) -> np.ndarray:
        """n joint posterior draws of the expensive level's mean function at X, shape (n, len(X))."""
        return self.rho_ * self.lo_.draws(X, n, rng) + self.delta_.draws(X, n, rng)

    def describe(self) -> dict:
        return {"kind": self.kind, "rho": self.rho_, "cheap": self.lo_.describe(), "discrepancy": self.delta_.describe()}
