"""The interface the map-level criteria and the active batches need from a fitted model.

The interface (all that ``map_criteria`` and ``active`` use)
-----------------------------------------------------------
A *map model* is a fitted model of one target (MFR or PD) over the design inputs, in physical
units and ``design.NAMES`` order (f, d_um, h_um, v_mm_s), with

* ``predict(X, return_std=True) -> (mean[n], sd[n])``: the posterior mean of the noise-free
  response and its standard deviation (the model's uncertainty about the *map*, not the noise of
  a new case); ``predict(X)`` returns the mean alone;
* ``noise_sd: float``: the model's estimate of one case's noise SD (target units), used when the
  table carries no per-case noise.

A *fit function* ``fit(X[n, 4], y[n], noise_sd[n] or None) -> map model`` builds one from data;
``fit_table(table, target, fit)`` applies it to the usable rows of a results table (per-case
noise from the ``{target}_sd`` column when the table has one).

Active batches need one thing more, the posterior covariance between points, which a Gaussian
process has in closed form: ``GPMapModel.posterior_cov``.  ``active`` uses it when present and
falls back to "largest posterior SD, one point at a time, no update" for any other model.

The model behind the interface here
-----------------------------------
``fit_gp``: scikit-learn's ``GaussianProcessRegressor`` on inputs scaled to the unit cube and
standardised outputs, kernel ``C * Matern(nu=2.5, one length scale per input) + White``.  The
white term is the noise the data show beyond any per-case noise given (``alpha``, the per-case
variance, on the diagonal), so the GP smooths the noise instead of fitting it.  Hyperparameters
by maximum marginal likelihood (L-BFGS-B, ``n_restarts`` restarts, seeded).  This is a stand-in
with the same interface as the project's noise-aware surrogate; the workflow can pass that
surrogate's fit function instead.
"""
from __future__ import annotations

import warnings
from typing import Callable, Protocol

import numpy as np
import pandas as pd
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

from ..design import NAMES, to_unit
from ..table import usable


class MapModel(Protocol):
    noise_sd: float

    def predict(self, X, return_std: bool = False): ...


FitFunction = Callable[[np.ndarray, np.ndarray, "np.ndarray | None"], MapModel]


class GPMapModel:
    """A fitted GP behind the map-model interface (see the module docstring)."""

    def __init__(self, gp: GaussianProcessRegressor, ranges: dict | None, y_scale: float,
                 case_noise_var: np.ndarray | None):
        self.gp = gp
        self.ranges = ranges
        self._y_scale = float(y_scale)  # sklearn's normalize_y scale (target units)
        k = gp.kernel_
        self.latent_kernel = k.k1  # C * Matern, in standardised units
        self.white_var = float(k.k2.noise_level)  # standardised units
        self._case_var = case_noise_var  # per-case noise variance (standardised), or None
        typical = self.white_var + (float(np.mean(case_noise_var)) if case_noise_var is not None else 0.0)
        self.noise_sd = float(np.sqrt(typical) * self._y_scale)

    def _unit(self, X) -> np.ndarray:
        return to_unit(np.asarray(X, float), self.ranges)

    def predict(self, X, return_std: bool = False):
        mean, sd = self.gp.predict(self._unit(X), return_std=True)
        if not return_std:
            return mean
        # sklearn's sd includes the white (noise) variance: take it out to get the map's SD
        var = np.maximum(sd**2 - self.white_var * self._y_scale**2, 0.0)
        return mean, np.sqrt(var)

    # ---- what active batches use (standardised units; the scale cancels in the ratios) ----
    @property
    def X_train_unit(self) -> np.ndarray:
        return self.gp.X_train_

    def train_noise_var(self) -> np.ndarray:
        """Noise variance on the diagonal for each training case (standardised units)."""
        n = self.gp.X_train_.shape[0]
        case = self._case_var if self._case_var is not None else np.zeros(n)
        return case + self.white_var

    def new_case_noise_var(self) -> float:
        """Noise variance of a case not yet run (standardised units): the typical one."""
        return (self.noise_sd / self._y_scale) ** 2

    def posterior_cov(self, A_unit: np.ndarray, B_unit: np.ndarray) -> np.ndarray:
        """Posterior covariance of the noise-free response between unit-cube points A and B."""
        X = self.gp.X_train_
        K = self.latent_kernel(X) + np.diag(self.train_noise_var())
        L = np.linalg.cholesky(K + 1e-10 * np.eye(len(X)))
        va = np.linalg.solve(L, self.latent_kernel(X, A_unit))
        vb = va if B_unit is A_unit else np.linalg.solve(L, self.latent_kernel(X, B_unit))
        return self.latent_kernel(A_unit, B_unit) - va.T @ vb

    def posterior_var(self, A_unit: np.ndarray) -> np.ndarray:
        X = self.gp.X_train_
        K = self.latent_kernel(X) + np.diag(self.train_noise_var())
        L = np.linalg.cholesky(K + 1e-10 * np.eye(len(X)))
        v = np.linalg.solve(L, self.latent_kernel(X, A_unit))
        return np.maximum(self.latent_kernel.diag(A_unit) - np.sum(v**2, axis=0), 0.0)


def make_gp_fit(ranges: dict | None = None, nu: float = 2.5, n_restarts: int = 0,
                seed: int = 0) -> FitFunction:
    """A fit function ``fit(X, y, noise_sd=None) -> GPMapModel`` (see the module docstring).

    Every fit starts from the same initial hyperparameters (no warm start: measured, a start
    from the previous batch's optimum carries a noise-interpolating optimum of a small sample,
    which maximum likelihood can prefer at ~32 cases, on to every later batch).
    """

    def fit(X, y, noise_sd=None) -> GPMapModel:
        X = np.asarray(X, float)
        y = np.asarray(y, float)
        if X.ndim != 2 or X.shape[1] != len(NAMES) or len(X) != len(y):
            raise ValueError(f"fit needs X[n, {len(NAMES)}] and y[n]; got {X.shape} and {y.shape}")
        if len(y) < 3:
            raise ValueError(f"fit needs at least 3 cases, got {len(y)}")
        scale = float(np.std(y)) or 1.0
        case_var = None
        alpha = 1e-10
        if noise_sd is not None:
            sd = np.asarray(noise_sd, float)
            if sd.shape != y.shape or not np.all(np.isfinite(sd)) or np.any(sd < 0):
                raise ValueError("noise_sd must be finite, >= 0 and one per case")
            case_var = (sd / scale) ** 2
            alpha = case_var + 1e-10
        # the start: a smooth model with a tenth of the variance as noise (measured: a start at
        # length 0.5 and noise 0.01 ended in a rougher optimum of lower likelihood, map error 2x)
        kernel = (ConstantKernel(1.0, (1e-3, 1e3))
                  * Matern(length_scale=np.full(len(NAMES), 1.0), length_scale_bounds=(1e-2, 1e2), nu=nu)
                  + WhiteKernel(0.1, (1e-6, 1.0)))
        gp = GaussianProcessRegressor(kernel=kernel, alpha=alpha, normalize_y=True,
                                      n_restarts_optimizer=n_restarts, random_state=seed)
        with warnings.catch_warnings():  # hyperparameters at a bound are legitimate here
            warnings.simplefilter("ignore", ConvergenceWarning)
            gp.fit(to_unit(X, ranges), y)
        return GPMapModel(gp, ranges, gp._y_train_std, case_var)

    return fit


def usable_rows(table: pd.DataFrame, target: str) -> pd.DataFrame:
    """The rows of a results table a model of ``target`` is fitted on: usable, target finite."""
    ok = usable(table) & np.isfinite(pd.to_numeric(table[target], errors="coerce")).to_numpy()
    return table[ok]


def table_data(table: pd.DataFrame, target: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(X, y, per-case noise SD or None) of the usable rows of a results table for one target
    (``usable_rows``, in their order).

    The per-case noise is the column ``{target}_sd`` when the table has it (rows where it is
    missing get the median of the others); otherwise None (the model estimates the noise).
    """
    rows = usable_rows(table, target)
    X = rows[list(NAMES)].to_numpy(float)
    y = rows[target].to_numpy(float)
    col = f"{target}_sd"
    sd = None
    if col in rows.columns:
        s = pd.to_numeric(rows[col], errors="coerce").to_numpy(float)
        good = np.isfinite(s) & (s >= 0)
        if good.any():
            sd = np.where(good, s, np.median(s[good]))
    return X, y, sd


def fit_table(table: pd.DataFrame, target: str, fit: FitFunction) -> MapModel:
    """Fit one map model to the usable rows of a results table (see ``table_data``)."""
    X, y, sd = table_data(table, target)
    return fit(X, y, sd)
