"""The reference study's protocol, run as the study ran it and reported beside the validation.

scikit-learn ``MLPRegressor`` with one hidden layer; inputs and targets scaled (StandardScaler);
a hidden-neuron sweep (``neurons``), every size trained with each of ``seeds``; one 80/20 split
(``test_fraction``) by ``train_test_split`` with a fixed random state (``split_seed``); the
held-out R^2 per size, averaged over the seeds. Solver L-BFGS, tanh, alpha 1e-4 (scikit-learn's
default penalty), up to 5000 iterations. The size the study would pick is the one with the best
mean held-out R^2: chosen on the cases it is then scored on, so that R^2 is optimistic, and with
~20 % of a small table held out it rests on a handful of cases. Its numbers are a comparison, not
the validation of the maps (see ``validation``).
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
from sklearn.compose import TransformedTargetRegressor
from sklearn.exceptions import ConvergenceWarning
from sklearn.metrics import r2_score
from sklearn.model_selection import train_test_split
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from threadpoolctl import threadpool_limits

from .training_rows import TrainingRows


def study_mlp(neurons: int, seed: int) -> TransformedTargetRegressor:
    """One network of the study: scaled inputs, one hidden layer, scaled target."""
    mlp = MLPRegressor(hidden_layer_sizes=(int(neurons),), activation="tanh", solver="lbfgs", alpha=1e-4,
                       max_iter=5000, tol=1e-7, random_state=int(seed))
    return TransformedTargetRegressor(regressor=Pipeline([("scale", StandardScaler()), ("mlp", mlp)]),
                                      transformer=StandardScaler())


def split(n: int, cfg: dict) -> tuple[np.ndarray, np.ndarray]:
    """The study's one split of n cases: (training indices, held-out indices)."""
    tr, te = train_test_split(np.arange(n), test_size=float(cfg["test_fraction"]), random_state=int(cfg["split_seed"]))
    return tr, te


def run_protocol(rows: TrainingRows, targets, cfg: dict) -> pd.DataFrame:
    """One row per (target, neurons, seed): r2_test, r2_train, n_train, n_test, converged."""
    X = rows.X
    tr, te = split(len(rows), cfg)
    out = []
    for t in targets:
        y = rows.y(t)
        for n in cfg["neurons"]:
            for s in cfg["seeds"]:
                est = study_mlp(n, s)
                with threadpool_limits(1), warnings.catch_warnings(record=True) as w:
                    warnings.simplefilter("always", ConvergenceWarning)
                    est.fit(X[tr], y[tr])
                out.append({"target": t, "neurons": int(n), "seed": int(s),
                            "r2_test": float(r2_score(y[te], est.predict(X[te]))),
                            "r2_train": float(r2_score(y[tr], est.predict(X[tr]))),
                            "n_train": len(tr), "n_test": len(te),
                            "converged": not any(issubclass(x.category, ConvergenceWarning) for x in w)})
    return pd.DataFrame(out)


def summary(runs: pd.DataFrame) -> pd.DataFrame:
    """Per (target, neurons): held-out R^2 mean, min, max over the seeds, training R^2, and the size
    the study would choose (best mean held-out R^2; ties: the smaller network)."""
    s = (runs.groupby(["target", "neurons"], sort=False)
         .agg(r2_mean=("r2_test", "mean"), r2_min=("r2_test", "min"), r2_max=("r2_test", "max"),
              r2_train_mean=("r2_train", "mean"), n_seeds=("seed", "count"),
              n_train=("n_train", "first"), n_test=("n_test", "first"))
         .reset_index())
    best = s.groupby("target")["r2_mean"].transform("max")
    first = s[s["r2_mean"] == best].groupby("target")["neurons"].transform("min")
    s["chosen"] = False
    s.loc[first.index, "chosen"] = s.loc[first.index, "neurons"] == first
    return s
