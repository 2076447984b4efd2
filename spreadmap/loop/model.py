"""The loop's model is the map's model: the surrogate that draws the maps, behind the small
interface the loop's criteria and its batches need.

One model
---------
The main job used to decide with a stand-in GP (raw unit inputs, its own noise handling) and draw
the maps with the surrogate (``spreadmap.surrogate.models``: physics inputs f, ln d, ln(h/d), v,
per-case calibrated noise). The two disagreed about how good the map was (at 152 cases of the
study: MFR's CV RMSE 1.15x the noise for the surrogate, ~1.48x for the stand-in), so "converged"
was said of a model the user never saw. Here the loop fits exactly the class, inputs, kernel and
noise model that ``surrogate.fitting.fit_surrogate`` fits for the maps (``make_model`` with the
``surrogate:`` config), on the same usable rows and the same calibrated per-case SDs.

The interface (all that ``map_criteria`` and ``active`` use)
-----------------------------------------------------------
A *map model* of one target, inputs in physical units and ``design.NAMES`` order:

* ``predict(X, return_std=True) -> (mean[n], sd[n])``: the posterior mean of the noise-free
  response and its SD (the model's uncertainty about the *map*, not a new run's noise);
* ``noise_sd: float``: the RMS noise SD of one run over the training cases (target units);
* ``run_sd(X)``: the noise SD of one new run at X (the per-case noise model);
* ``draws(X, n, rng)``: joint posterior draws of the map at X, shape (n, len(X)).

Gaussian processes add what the greedy batch needs (exact posterior covariances, in the model's
standardised units): ``embed``, ``latent_kernel``, ``X_train_embedded``, ``train_noise_var`` and
``new_case_noise_var``. An MLP ensemble has none of these: ``active`` then falls back to the
largest model SD with an exclusion radius.

A *fit function* ``fit(X[n, 4], y[n], noise_sd[n] or None) -> map model`` builds one
(``make_map_fit``); ``fit_table`` applies it to the usable rows of a results table.
"""
from __future__ import annotations

from typing import Callable, Mapping, Protocol

import numpy as np
import pandas as pd

from ..design import NAMES
from ..table import usable_cases

MODEL_KINDS = ("gp", "mlp")


class MapModel(Protocol):
    noise_sd: float

    def predict(self, X, return_std: bool = False): ...


FitFunction = Callable[[np.ndarray, np.ndarray, "np.ndarray | None"], MapModel]


class SurrogateMapModel:
    """A fitted ``surrogate.models`` model (GP or MLP ensemble) behind the map-model interface."""

    def __init__(self, model, X_train: np.ndarray):
        self.model = model
        self.kind = model.kind
        self.noise_sd = float(np.sqrt(np.mean(model.noise_sd(np.asarray(X_train, float)) ** 2)))

    def predict(self, X, return_std: bool = False):
        mean, sd = self.model.latent(np.asarray(X, float))
        return (mean, sd) if return_std else mean

    def run_sd(self, X) -> np.ndarray:
        return self.model.noise_sd(np.asarray(X, float))

    def draws(self, X, n: int, rng) -> np.ndarray:
        return self.model.draws(np.asarray(X, float), n, rng)

    # ---- what the greedy batch uses (GP only; standardised target units) ----------------------
    @property
    def has_covariance(self) -> bool:
        return self.kind == "gp"

    def embed(self, X) -> np.ndarray:
        """Physical points in the model's input space (its features, standardised on its cases)."""
        return self.model.scale_(np.asarray(X, float))

    @property
    def latent_kernel(self):
        if self.kind != "gp":
            raise AttributeError(f"a {self.kind} model has no kernel")
        return self.model.signal_

    @property
    def X_train_embedded(self) -> np.ndarray:
        return self.model.gp_.X_train_

    def train_noise_var(self) -> np.ndarray:
        """Noise variance on the diagonal for each training case (per-case and excess)."""
        alpha = np.broadcast_to(np.asarray(self.model.gp_.alpha, float), (len(self.X_train_embedded),))
        return alpha + self.model.excess_var_

    def new_case_noise_var(self, X) -> np.ndarray:
        """Noise variance of a new run at each physical point X."""
        return (self.run_sd(X) / self.model.y_sd_) ** 2


def surrogate_settings(surrogate_cfg: Mapping | None) -> dict:
    """The surrogate's effective config (schema defaults filled)."""
    from ..surrogate.settings import make_config

    return make_config(dict(surrogate_cfg or {}))


def loop_kind(cfg: Mapping) -> str:
    """The model kind the loop fits: the map model's (``gp`` or ``mlp``); with ``best``, which the
    surrogate decides per target by validation after the run, the loop decides with the GP."""
    return cfg["model"] if cfg["model"] in MODEL_KINDS else "gp"


def make_map_fit(surrogate_cfg: Mapping | None = None, final: bool = False) -> FitFunction:
    """``fit(X, y, noise_sd=None) -> SurrogateMapModel``: the surrogate's map model of one target
    (``final``: with the final fit's optimizer restarts, as the model the maps are drawn from).

    Parameters
    ----------
    surrogate_cfg : Mapping or None, optional
        The config's ``surrogate:`` section (schema defaults filled in); its ``model`` picks the
        kind (``gp`` or ``mlp``; ``best`` fits the GP, see ``loop_kind``).
    final : bool, optional
        Fit with the final fit's optimizer restarts instead of the loop's.

    Returns
    -------
    FitFunction
        ``fit(X, y, noise_sd=None)``: X shape (n, 4) in physical units and ``design.NAMES``
        order, y shape (n,) in the target's units, noise_sd the per-case noise SD (same units)
        or None; returns a ``SurrogateMapModel``. It raises ValueError if the shapes do not match,
        if n < 3, or if noise_sd is not finite, >= 0 and one per case.
    """
    from ..surrogate.models import make_model

    cfg = surrogate_settings(surrogate_cfg)
    kind = loop_kind(cfg)

    def fit(X, y, noise_sd=None) -> SurrogateMapModel:
        X = np.asarray(X, float)
        y = np.asarray(y, float)
        if X.ndim != 2 or X.shape[1] != len(NAMES) or len(X) != len(y):
            raise ValueError(f"fit needs X[n, {len(NAMES)}] and y[n]; got {X.shape} and {y.shape}")
        if len(y) < 3:
            raise ValueError(f"fit needs at least 3 cases, got {len(y)}")
        sd = None
        if noise_sd is not None:
            sd = np.asarray(noise_sd, float)
            if sd.shape != y.shape or not np.all(np.isfinite(sd)) or np.any(sd < 0):
                raise ValueError("noise_sd must be finite, >= 0 and one per case")
        return SurrogateMapModel(make_model(kind, cfg, final=final).fit(X, y, sd), X)

    return fit


def table_data(table: pd.DataFrame, target: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(X, y, per-case noise SD or None) of the usable rows of a results table for one target
    (``table.usable_cases`` with the target finite, in their order).

    The per-case noise is the column ``{target}_sd`` when the table has it (rows where it is
    missing get the median of the others); otherwise None (the model estimates the noise).
    """
    rows = usable_cases(table, [target])
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
