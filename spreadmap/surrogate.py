"""MLP surrogates of MFR and PD: the study's protocol, validation beyond it, and prediction.

The study's protocol
--------------------
* scikit-learn ``MLPRegressor`` with ONE hidden layer; inputs AND targets scaled;
* a hidden-neuron sweep (config ``neurons``), every size trained with three seeds (``seeds``),
  the held-out R^2 averaged over the seeds (min and max reported too);
* one 80/20 train/test split with a fixed random state shared by all partitions;
* parity data (DEM against predicted on the held-out cases) with the slope and intercept of the
  least-squares line (``scipy.stats.linregress``).

Design decisions
----------------
* **Separate models for MFR and PD.**  Each target gets its own network (and its own neuron
  count): the two responses have different shapes (MFR collapses to 0 at jamming, PD saturates),
  so a shared hidden layer would force one compromise size on both, and a per-target R^2 is what
  the study reports anyway.
* **Estimator** (one per target, per seed)::

      TransformedTargetRegressor(
          regressor=Pipeline([("scale", StandardScaler()),          # or MinMaxScaler
                              ("mlp", MLPRegressor(hidden_layer_sizes=(n,), ...))]),
          transformer=StandardScaler())                               # the target is scaled too

* **Solver**: L-BFGS (``solver="lbfgs"``), ``activation="tanh"``, ``alpha=1e-4``,
  ``max_iter=5000``, ``tol=1e-7``.  With a few hundred to a few thousand cases and a smooth
  response, full-batch L-BFGS converges to a far tighter optimum than Adam and is deterministic
  for a given ``random_state``.  Early stopping exists only for ``adam``/``sgd`` in scikit-learn;
  it is passed through when one of those solvers is configured (``early_stopping: true``) and is
  irrelevant for L-BFGS, which stops on ``tol``/``max_iter``.  Whether each fit converged
  (``n_iter_ < max_iter`` and no ``ConvergenceWarning``) is recorded, never hidden.
* **BLAS threads**: every fit runs with BLAS limited to ``blas_threads`` (default 1) through
  threadpoolctl.  These matrices are tiny; multi-threaded BLAS made a fit 5-10x slower on the
  2-core machine.  Parallelism, if wanted, is across fits (``n_jobs``, joblib); it gives the
  same numbers bit for bit (each fit has its own seed), but for small tables the worker start-up
  costs more than it saves.
* **Split rule** (the "fixed random state shared by all partitions"): every case gets a number
  ``u = SHA-256("<split_seed>|<case_id>")[:8] / 2**64`` in [0, 1); it is a test case iff
  ``u < test_fraction``.  Membership depends only on the case identity and the seed, never on
  the partition size, so the test set of LDS-N1 is the test set of LDS-N2 restricted to the
  first N1 cases, a case never changes side when the sample grows, and no model trained on a
  small partition has seen a test case of a larger one.  (``train_test_split(random_state=...)``
  does not have this property: it re-shuffles when N changes.  Splitting by ``index % 5`` is
  avoided on purpose: Halton's third coordinate has base 5, so ``index % 5`` would put the whole
  test set in one slab of h.)  The test fraction is 20 % in expectation, not exactly; the counts
  are reported.
* **Cross-validation**: k folds (default 5) by the same number ``u``: fold ``floor(u * k)``.
  With ``test_fraction = 1/k`` fold 0 *is* the held-out set.  The CV runs over all usable cases
  (train and test) with the first seed, for every neuron count (``cv_all_neurons``) or only the
  chosen one.  Choosing the neuron count on the held-out R^2 makes that R^2 slightly optimistic;
  the CV R^2 is the independent check.
* **Model choice**: per target the neuron count with the best mean held-out R^2 (ties: the
  smaller network).  The saved model is an ensemble of ``ensemble_members`` networks of that size
  (the sweep seeds first, then further seeds; optional bootstrap resampling); the ensemble mean
  is the prediction and the member standard deviation (ddof=1) its uncertainty.  The members are
  trained on the training split (``final_fit: "train"``, the default, so the recorded test R^2 is
  the R^2 of the saved model) or refitted on all usable cases (``final_fit: "all"``; the recorded
  test R^2 then comes from the train-split ensemble).
* **Baseline**: a Gaussian process per target on the same split (constant x anisotropic Matern
  5/2 or RBF + WhiteKernel, ``normalize_y=True``, inputs scaled like the MLP's), with
  ``gp_restarts`` optimizer restarts on the main split and none in the CV folds and the learning
  curve (cost).
* **Learning curve**: held-out R^2 against the number of LDS cases used, in prefix order of
  ``index``; always evaluated on the same held-out cases (the test cases of the full table), so
  the points are comparable.
* **Training range**: the min/max of every parameter over the fitted rows, widened by
  ``range_tolerance`` (default 1 %) of the span, because a finite LDS sample never touches the
  design bounds exactly.  Points outside get ``outside_training_range = True`` and a
  ``OutOfRangeWarning`` naming the parameter, the value and the range.  Predictions are not
  clipped to [0, 0.7405].

Only load model files you trust: joblib files are pickles.
"""
from __future__ import annotations

import argparse
import copy
import hashlib
import io
import json
import math
import platform
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import joblib
import numpy as np
import pandas as pd
import scipy
import sklearn
from scipy import stats
from sklearn.compose import TransformedTargetRegressor
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Matern, WhiteKernel
from sklearn.metrics import r2_score
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import MinMaxScaler, StandardScaler
from threadpoolctl import threadpool_limits

from .design import BY_NAME, NAMES, TARGETS

FORMAT = "spreadmap-surrogate/1"
EXCLUSION_REASONS = ("failed", "blown", "flagged", "nonfinite")

DEFAULT_CONFIG: dict = {
    "neurons": [4, 8, 16, 32, 64],   # hidden-layer sizes of the sweep
    "seeds": [0, 1, 2],              # network initialisation seeds, per size
    "test_fraction": 0.2,
    "split_seed": 0,                 # the fixed random state of the split (a hash salt)
    "scaler": "standard",            # "standard" | "minmax", inputs and targets
    "activation": "tanh",
    "solver": "lbfgs",
    "alpha": 1e-4,
    "max_iter": 5000,
    "tol": 1e-7,
    "early_stopping": False,         # adam / sgd only
    "cv_folds": 5,
    "cv_all_neurons": True,
    "gp": True,
    "gp_kernel": "matern",           # "matern" (nu = 2.5) | "rbf"
    "gp_restarts": 2,
    "ensemble_members": 5,
    "bootstrap": False,
    "final_fit": "train",            # "train" | "all"
    "learning_curve": "auto",        # "auto" | list of prefix sizes | None
    "learning_curve_sweep": "lds",   # sweep whose index prefix is grown; None: all rows
    "range_tolerance": 0.01,         # fraction of the trained span
    "n_jobs": 1,
    "blas_threads": 1,
}

MIN_TRAIN = 8
MIN_TEST = 2


class OutOfRangeWarning(UserWarning):
    """A prediction was requested outside the parameter ranges the surrogate was trained on."""


# --------------------------------------------------------------------------------------------
# configuration
# --------------------------------------------------------------------------------------------
def make_config(config: Mapping | None = None) -> dict:
    """The effective configuration: defaults overridden by ``config``; unknown keys refused."""
    config = dict(config or {})
    unknown = sorted(set(config) - set(DEFAULT_CONFIG))
    if unknown:
        raise ValueError(f"unknown surrogate config key(s) {unknown}; known: {sorted(DEFAULT_CONFIG)}")
    cfg = copy.deepcopy(DEFAULT_CONFIG)
    cfg.update(copy.deepcopy(config))
    cfg["neurons"] = [int(n) for n in cfg["neurons"]]
    cfg["seeds"] = [int(s) for s in cfg["seeds"]]
    if not cfg["neurons"] or min(cfg["neurons"]) < 1:
        raise ValueError(f"neurons must be a non-empty list of positive integers, got {cfg['neurons']}")
    if not cfg["seeds"]:
        raise ValueError("seeds must be a non-empty list of integers")
    if not 0.0 < float(cfg["test_fraction"]) < 1.0:
        raise ValueError(f"test_fraction must be in (0, 1), got {cfg['test_fraction']}")
    if cfg["scaler"] not in ("standard", "minmax"):
        raise ValueError(f"scaler must be 'standard' or 'minmax', got {cfg['scaler']!r}")
    if cfg["gp_kernel"] not in ("matern", "rbf"):
        raise ValueError(f"gp_kernel must be 'matern' or 'rbf', got {cfg['gp_kernel']!r}")
    if cfg["final_fit"] not in ("train", "all"):
        raise ValueError(f"final_fit must be 'train' or 'all', got {cfg['final_fit']!r}")
    if int(cfg["ensemble_members"]) < 2:
        raise ValueError("ensemble_members must be >= 2 (the spread of the members is the uncertainty)")
    if int(cfg["cv_folds"]) < 2:
        raise ValueError("cv_folds must be >= 2")
    if float(cfg["range_tolerance"]) < 0:
        raise ValueError("range_tolerance must be >= 0")
    return cfg


# --------------------------------------------------------------------------------------------
# training rows
# --------------------------------------------------------------------------------------------
def _as_bool(series: pd.Series, name: str) -> np.ndarray:
    if series.dtype == bool:
        return series.to_numpy()
    out = []
    for i, v in zip(series.index, series):
        if isinstance(v, (bool, np.bool_)):
            out.append(bool(v))
        elif isinstance(v, (int, np.integer)) and v in (0, 1):
            out.append(bool(v))
        elif isinstance(v, (float, np.floating)) and v in (0.0, 1.0):
            out.append(bool(v))
        elif isinstance(v, str) and v.strip().lower() in ("true", "false", "1", "0"):
            out.append(v.strip().lower() in ("true", "1"))
        else:
            raise ValueError(f"column {name!r}: cannot read {v!r} (row {i}) as a boolean")
    return np.array(out, bool)


def select_training_rows(df: pd.DataFrame) -> tuple[pd.DataFrame, dict]:
    """Rows usable for training, and the number of excluded rows by reason.

    Usable: ``status == "ok"`` and not ``flagged`` with finite mfr and pd (and finite inputs).
    Reasons, each row counted once in this order: ``failed``, ``blown``, any other status by
    its name, ``flagged`` (ok but a diagnostic broke a bound), ``nonfinite`` (ok, not flagged,
    but mfr/pd/an input is NaN or inf).  Nothing is dropped without being counted.
    """
    required = ["case_id", "status", "flagged", *NAMES, *TARGETS]
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise ValueError(f"results table lacks column(s) {missing}")
    if df["case_id"].isna().any():
        raise ValueError("results table has rows without case_id")
    ids = df["case_id"].astype(str)
    dup = ids[ids.duplicated()].unique()
    if len(dup):
        raise ValueError(f"duplicate case_id(s) in the results table: {list(dup[:5])}")
    status = df["status"].astype(str).str.strip()
    flagged = _as_bool(df["flagged"], "flagged")
    values = df[[*NAMES, *TARGETS]].apply(pd.to_numeric, errors="coerce").to_numpy(float)
    finite = np.isfinite(values).all(axis=1)

    exclusions = {r: 0 for r in EXCLUSION_REASONS}
    ok = (status == "ok").to_numpy()
    for s, n in status[~ok].value_counts().items():
        exclusions[str(s)] = exclusions.get(str(s), 0) + int(n)
    exclusions["flagged"] = int((ok & flagged).sum())
    exclusions["nonfinite"] = int((ok & ~flagged & ~finite).sum())
    usable = ok & ~flagged & finite
    out = df.loc[usable].copy()
    out["case_id"] = out["case_id"].astype(str)
    for c in (*NAMES, *TARGETS):
        out[c] = pd.to_numeric(out[c]).astype(float)
    return out.reset_index(drop=True), exclusions


def partition(df: pd.DataFrame, n: int, sweep: str | None = "lds") -> pd.DataFrame:
    """The partition LDS-n: the rows of ``sweep`` whose ``index`` is below n (prefix order)."""
    rows = df
    if sweep is not None and "sweep" in df.columns:
        rows = rows[rows["sweep"].astype(str) == sweep]
    return rows[rows["index"].astype(int) < int(n)].sort_values("index").reset_index(drop=True)


# --------------------------------------------------------------------------------------------
# split
# --------------------------------------------------------------------------------------------
def split_number(case_ids: Sequence, seed: int = 0) -> np.ndarray:
    """A uniform number in [0, 1) per case: SHA-256 of "<seed>|<case_id>", first 8 bytes."""
    out = np.empty(len(case_ids), float)
    for i, cid in enumerate(case_ids):
        h = hashlib.sha256(f"{int(seed)}|{cid}".encode()).digest()
        out[i] = int.from_bytes(h[:8], "big") / 2.0**64
    return out


def test_mask(case_ids: Sequence, test_fraction: float = 0.2, seed: int = 0) -> np.ndarray:
    """True for the held-out cases; a function of each case's identity only (see module doc)."""
    return split_number(case_ids, seed) < float(test_fraction)


def fold_of(case_ids: Sequence, folds: int = 5, seed: int = 0) -> np.ndarray:
    """Cross-validation fold of each case, floor(u * folds) with the split's number u."""
    return np.minimum((split_number(case_ids, seed) * folds).astype(int), folds - 1)


# --------------------------------------------------------------------------------------------
# estimators
# --------------------------------------------------------------------------------------------
def _scaler(cfg: dict):
    return StandardScaler() if cfg["scaler"] == "standard" else MinMaxScaler()


def make_mlp(neurons: int, seed: int, cfg: dict) -> TransformedTargetRegressor:
    """One single-hidden-layer MLP with scaled inputs and a scaled target."""
    kw = dict(
        hidden_layer_sizes=(int(neurons),), activation=cfg["activation"], solver=cfg["solver"],
        alpha=float(cfg["alpha"]), max_iter=int(cfg["max_iter"]), tol=float(cfg["tol"]),
        random_state=int(seed),
    )
    if cfg["solver"] in ("adam", "sgd"):
        kw["early_stopping"] = bool(cfg["early_stopping"])
    mlp = MLPRegressor(**kw)
    return TransformedTargetRegressor(
        regressor=Pipeline([("scale", _scaler(cfg)), ("mlp", mlp)]), transformer=_scaler(cfg)
    )


def make_gp(cfg: dict, n_restarts: int | None = None) -> Pipeline:
    """Gaussian-process baseline: constant x anisotropic Matern 5/2 (or RBF) + white noise."""
    ls = np.ones(len(NAMES))
    if cfg["gp_kernel"] == "matern":
        base = Matern(length_scale=ls, length_scale_bounds=(1e-2, 1e3), nu=2.5)
    else:
        base = RBF(length_scale=ls, length_scale_bounds=(1e-2, 1e3))
    kernel = ConstantKernel(1.0, (1e-3, 1e3)) * base + WhiteKernel(1e-4, (1e-10, 1.0))
    gp = GaussianProcessRegressor(
        kernel=kernel, normalize_y=True,
        n_restarts_optimizer=int(cfg["gp_restarts"] if n_restarts is None else n_restarts),
        random_state=int(cfg["split_seed"]),
    )
    return Pipeline([("scale", _scaler(cfg)), ("gp", gp)])


def _fit_mlp_job(X, y, neurons, seed, cfg, rows=None):
    """Fit one MLP (top-level so that joblib can ship it to a worker)."""
    if rows is not None:
        X, y = X[rows], y[rows]
    est = make_mlp(neurons, seed, cfg)
    with threadpool_limits(limits=int(cfg["blas_threads"])), warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always", ConvergenceWarning)
        est.fit(X, y)
    n_iter = int(est.regressor_[-1].n_iter_)
    warned = any(issubclass(x.category, ConvergenceWarning) for x in w)
    converged = (not warned) and n_iter < int(cfg["max_iter"])
    return est, n_iter, converged


def _fit_gp_job(X, y, cfg, n_restarts=None):
    est = make_gp(cfg, n_restarts)
    with threadpool_limits(limits=int(cfg["blas_threads"])), warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always", ConvergenceWarning)
        est.fit(X, y)
    notes = sorted({str(x.message).split("\n")[0] for x in w if issubclass(x.category, ConvergenceWarning)})
    return est, notes


def _predict(est, X, cfg):
    with threadpool_limits(limits=int(cfg["blas_threads"])):
        return est.predict(X)


def _run(jobs: list, cfg: dict) -> list:
    """Run (function, args) jobs sequentially or with joblib; results in job order."""
    n_jobs = int(cfg["n_jobs"])
    if n_jobs == 1 or len(jobs) <= 1:
        return [f(*a) for f, a in jobs]
    return joblib.Parallel(n_jobs=n_jobs)(joblib.delayed(f)(*a) for f, a in jobs)


def _r2(y, p) -> float:
    return float(r2_score(y, p)) if len(y) >= MIN_TEST else float("nan")


# --------------------------------------------------------------------------------------------
# the saved model
# --------------------------------------------------------------------------------------------
@dataclass
class SurrogateModel:
    """Ensembles of MLPs, one ensemble per target; callable as ``model(points) -> (n, 2)``."""

    members: dict            # target -> list of fitted TransformedTargetRegressor
    neurons: dict            # target -> hidden-layer size
    train_low: np.ndarray    # observed training minimum per parameter, NAMES order
    train_high: np.ndarray
    range_tolerance: float
    metadata: dict = field(default_factory=dict)
    names: tuple = NAMES
    targets: tuple = TARGETS

    def bounds_with_tolerance(self) -> tuple[np.ndarray, np.ndarray]:
        span = self.train_high - self.train_low
        return self.train_low - self.range_tolerance * span, self.train_high + self.range_tolerance * span

    def predict_members(self, X: np.ndarray) -> dict:
        """Member predictions, target -> array (members, n), for validated X (n, 4)."""
        with threadpool_limits(limits=1):
            return {t: np.vstack([m.predict(X) for m in self.members[t]]) for t in self.targets}

    def __call__(self, points) -> np.ndarray:
        """Predictor convention of the package: points (n, 4) physical, NAMES order -> (n, 2)."""
        out = predict(self, points)
        return out[list(self.targets)].to_numpy(float)


def _ensemble_stats(member_preds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return member_preds.mean(axis=0), member_preds.std(axis=0, ddof=1)


# --------------------------------------------------------------------------------------------
# result of a training run
# --------------------------------------------------------------------------------------------
@dataclass
class SurrogateResult:
    config: dict                 # effective configuration
    config_passed: dict          # what the caller passed
    exclusions: dict
    split: pd.DataFrame          # case_id, u, is_test, fold
    runs: pd.DataFrame           # target, neurons, seed, r2_test, r2_train, n_iter, converged
    summary: pd.DataFrame        # target, neurons, r2_mean/min/max, r2_train_mean, cv, chosen
    cv: pd.DataFrame             # target, model, neurons, fold, n_fit, n_eval, r2
    gp: pd.DataFrame             # target, r2_test, cv_r2_mean, cv_r2_std, kernel, notes
    learning: pd.DataFrame       # target, n_cases, n_train, n_test, r2_mean/min/max, gp_r2
    parity: pd.DataFrame         # target, case_id, dem, predicted, predicted_std
    parity_fit: pd.DataFrame     # target, slope, intercept, r_value, r2, stderr, n
    chosen: dict                 # target -> neurons
    ensemble_r2: dict            # target -> held-out R^2 of the ensemble mean
    model: SurrogateModel
    notes: list = field(default_factory=list)

    @property
    def n_train(self) -> int:
        return int((~self.split["is_test"]).sum())

    @property
    def n_test(self) -> int:
        return int(self.split["is_test"].sum())


def canonical_csv(rows: pd.DataFrame) -> bytes:
    """Canonical CSV of training rows: case_id, NAMES, TARGETS; sorted by case_id; repr floats."""
    cols = ["case_id", *NAMES, *TARGETS]
    r = rows[cols].copy()
    r["case_id"] = r["case_id"].astype(str)
    r = r.sort_values("case_id", kind="mergesort")
    lines = [",".join(cols)]
    for rec in r.itertuples(index=False):
        lines.append(",".join([str(rec[0]), *(repr(float(x)) for x in rec[1:])]))
    return ("\n".join(lines) + "\n").encode()


def sha256_rows(rows: pd.DataFrame) -> str:
    return hashlib.sha256(canonical_csv(rows)).hexdigest()


def versions() -> dict:
    return {
        "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
        "sklearn": sklearn.__version__, "pandas": pd.__version__, "joblib": joblib.__version__,
    }


def _jsonable(obj):
    if isinstance(obj, Mapping):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [_jsonable(v) for v in obj.tolist()]
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (str, int)) or obj is None:
        return obj
    if isinstance(obj, Path):
        return str(obj)
    return str(obj)


# --------------------------------------------------------------------------------------------
# training
# --------------------------------------------------------------------------------------------
def _auto_sizes(n_total: int) -> list[int]:
    sizes = sorted({int(round(n_total * f)) for f in (0.125, 0.25, 0.5, 1.0)})
    return [s for s in sizes if s >= 20] or [n_total]


def fit_surrogate(df: pd.DataFrame, config: Mapping | None = None, *,
                  source_path: str | Path | None = None) -> SurrogateResult:
    """Train, validate and choose the surrogate on a results table (see module docstring).

    ``df`` is the partition to train on (e.g. ``partition(results, 1000)``); unusable rows are
    excluded and counted in ``result.exclusions``.  ``source_path``: the table file, whose
    SHA-256 is then recorded too.
    """
    cfg = make_config(config)
    config_passed = copy.deepcopy(dict(config or {}))
    data, exclusions = select_training_rows(df)
    ids = data["case_id"].to_numpy()
    u = split_number(ids, cfg["split_seed"])
    is_test = u < float(cfg["test_fraction"])
    folds = np.minimum((u * int(cfg["cv_folds"])).astype(int), int(cfg["cv_folds"]) - 1)
    split = pd.DataFrame({"case_id": ids, "u": u, "is_test": is_test, "fold": folds})
    n_train, n_test = int((~is_test).sum()), int(is_test.sum())
    if n_train < MIN_TRAIN or n_test < MIN_TEST:
        raise ValueError(
            f"too few usable cases to train and test: {len(data)} usable ({n_train} train, "
            f"{n_test} test; need >= {MIN_TRAIN} and >= {MIN_TEST}); excluded: {exclusions}")
    X = data[list(NAMES)].to_numpy(float)
    Y = {t: data[t].to_numpy(float) for t in TARGETS}
    tr, te = ~is_test, is_test
    notes: list[str] = []

    # ---- hidden-neuron sweep: every size x seed x target on the one split ------------------
    keys = [(t, n, s) for t in TARGETS for n in cfg["neurons"] for s in cfg["seeds"]]
    fits = _run([(_fit_mlp_job, (X[tr], Y[t][tr], n, s, cfg)) for t, n, s in keys], cfg)
    fitted = {}
    rows = []
    for (t, n, s), (est, n_iter, conv) in zip(keys, fits):
        fitted[(t, n, s)] = est
        rows.append(dict(target=t, neurons=n, seed=s,
                         r2_test=_r2(Y[t][te], _predict(est, X[te], cfg)),
                         r2_train=_r2(Y[t][tr], _predict(est, X[tr], cfg)),
                         n_iter=n_iter, converged=conv))
    runs = pd.DataFrame(rows)
    if not runs["converged"].all():
        bad = runs.loc[~runs["converged"], ["target", "neurons", "seed"]].to_dict("records")
        notes.append(f"MLP fits that hit max_iter without converging: {bad}")
    g = runs.groupby(["target", "neurons"], sort=False)
    summary = g.agg(r2_mean=("r2_test", "mean"), r2_min=("r2_test", "min"), r2_max=("r2_test", "max"),
                    r2_train_mean=("r2_train", "mean"), n_converged=("converged", "sum"),
                    n_seeds=("seed", "count")).reset_index()
    chosen = {}
    for t in TARGETS:
        st = summary[summary["target"] == t]
        best = st["r2_mean"].max()
        chosen[t] = int(st.loc[st["r2_mean"] == best, "neurons"].min())
    summary["chosen"] = [chosen[t] == n for t, n in zip(summary["target"], summary["neurons"])]

    # ---- k-fold cross-validation over all usable cases ---------------------------------------
    k = int(cfg["cv_folds"])
    seed0 = cfg["seeds"][0]
    cv_keys = []
    for t in TARGETS:
        sizes = cfg["neurons"] if cfg["cv_all_neurons"] else [chosen[t]]
        for n in sizes:
            for j in range(k):
                if (folds == j).sum() >= MIN_TEST and (folds != j).sum() >= MIN_TRAIN:
                    cv_keys.append((t, n, j))
    cv_fits = _run([(_fit_mlp_job, (X[folds != j], Y[t][folds != j], n, seed0, cfg))
                    for t, n, j in cv_keys], cfg)
    cv_rows = [dict(target=t, model="mlp", neurons=n, fold=j, n_fit=int((folds != j).sum()),
                    n_eval=int((folds == j).sum()),
                    r2=_r2(Y[t][folds == j], _predict(est, X[folds == j], cfg)))
               for (t, n, j), (est, _, _) in zip(cv_keys, cv_fits)]

    # ---- Gaussian-process baseline -----------------------------------------------------------
    gp_rows, gp_fitted = [], {}
    if cfg["gp"]:
        gp_jobs = [(_fit_gp_job, (X[tr], Y[t][tr], cfg)) for t in TARGETS]
        gp_cv_keys = [(t, j) for t in TARGETS for j in range(k)
                      if (folds == j).sum() >= MIN_TEST and (folds != j).sum() >= MIN_TRAIN]
        gp_jobs += [(_fit_gp_job, (X[folds != j], Y[t][folds != j], cfg, 0)) for t, j in gp_cv_keys]
        gp_fits = _run(gp_jobs, cfg)
        for (t, j), (est, _) in zip(gp_cv_keys, gp_fits[len(TARGETS):]):
            cv_rows.append(dict(target=t, model="gp", neurons=np.nan, fold=j,
                                n_fit=int((folds != j).sum()), n_eval=int((folds == j).sum()),
                                r2=_r2(Y[t][folds == j], _predict(est, X[folds == j], cfg))))
        for t, (est, gp_notes) in zip(TARGETS, gp_fits[:len(TARGETS)]):
            gp_fitted[t] = est
            gp_rows.append(dict(target=t, r2_test=_r2(Y[t][te], _predict(est, X[te], cfg)),
                                kernel=str(est[-1].kernel_), notes="; ".join(gp_notes)))
    cv = pd.DataFrame(cv_rows, columns=["target", "model", "neurons", "fold", "n_fit", "n_eval", "r2"])
    cv_mlp = cv[cv["model"] == "mlp"].groupby(["target", "neurons"])["r2"].agg(["mean", "std"])
    summary["cv_r2_mean"] = [cv_mlp["mean"].get((t, n), np.nan) for t, n in zip(summary["target"], summary["neurons"])]
    summary["cv_r2_std"] = [cv_mlp["std"].get((t, n), np.nan) for t, n in zip(summary["target"], summary["neurons"])]
    gp = pd.DataFrame(gp_rows, columns=["target", "r2_test", "kernel", "notes"])
    if len(gp):
        cv_gp = cv[cv["model"] == "gp"].groupby("target")["r2"].agg(["mean", "std"])
        gp["cv_r2_mean"] = [cv_gp["mean"].get(t, np.nan) for t in gp["target"]]
        gp["cv_r2_std"] = [cv_gp["std"].get(t, np.nan) for t in gp["target"]]

    # ---- ensemble of the chosen size on the training split: parity and its R^2 ---------------
    m = int(cfg["ensemble_members"])
    member_seeds = list(cfg["seeds"][:m])
    nxt = max(cfg["seeds"]) + 1
    while len(member_seeds) < m:
        member_seeds.append(nxt)
        nxt += 1

    def boot_rows(n_rows, seed):
        rng = np.random.default_rng([int(cfg["split_seed"]), int(seed)])
        return rng.integers(0, n_rows, n_rows)

    def build_ensemble(Xf, Yf, reuse):
        members, jobs, slots = {t: [None] * m for t in TARGETS}, [], []
        for t in TARGETS:
            for i, s in enumerate(member_seeds):
                key = (t, chosen[t], s)
                if reuse and not cfg["bootstrap"] and key in fitted:
                    members[t][i] = fitted[key]
                else:
                    rows_ = boot_rows(len(Xf), s) if cfg["bootstrap"] else None
                    jobs.append((_fit_mlp_job, (Xf, Yf[t], chosen[t], s, cfg, rows_)))
                    slots.append((t, i))
        for (t, i), (est, _, _) in zip(slots, _run(jobs, cfg)):
            members[t][i] = est
        return members

    val_members = build_ensemble(X[tr], {t: Y[t][tr] for t in TARGETS}, reuse=True)
    parity_rows, fit_rows, ensemble_r2 = [], [], {}
    for t in TARGETS:
        P = np.vstack([_predict(e, X[te], cfg) for e in val_members[t]])
        mean, std = _ensemble_stats(P)
        ensemble_r2[t] = _r2(Y[t][te], mean)
        parity_rows.append(pd.DataFrame(dict(target=t, case_id=ids[te], dem=Y[t][te],
                                             predicted=mean, predicted_std=std)))
        lr = stats.linregress(Y[t][te], mean)
        fit_rows.append(dict(target=t, slope=float(lr.slope), intercept=float(lr.intercept),
                             r_value=float(lr.rvalue), r2=ensemble_r2[t], stderr=float(lr.stderr),
                             n=int(te.sum()), neurons=chosen[t]))
    parity = pd.concat(parity_rows, ignore_index=True)
    parity_fit = pd.DataFrame(fit_rows)

    # ---- final model ---------------------------------------------------------------------------
    if cfg["final_fit"] == "all":
        fit_mask = np.ones(len(data), bool)
        members = build_ensemble(X, Y, reuse=False)
    else:
        fit_mask = tr
        members = val_members
    fit_rows_df = data.loc[fit_mask]
    low = fit_rows_df[list(NAMES)].min().to_numpy(float)
    high = fit_rows_df[list(NAMES)].max().to_numpy(float)

    # ---- learning curve ---------------------------------------------------------------------
    learning = learning_curve(data, split, chosen, cfg, notes,
                              reuse={"mask": tr, "mlp": fitted, "gp": gp_fitted})

    s_idx = summary.set_index(["target", "neurons"])
    metadata = {
        "format": FORMAT,
        "model": "separate single-hidden-layer MLP ensembles for mfr and pd "
                 "(TransformedTargetRegressor(Pipeline([scaler, MLPRegressor])), target scaled)",
        "names": list(NAMES), "targets": list(TARGETS),
        "neurons": chosen, "members": m, "member_seeds": member_seeds, "bootstrap": bool(cfg["bootstrap"]),
        "final_fit": cfg["final_fit"],
        "config": cfg, "config_passed": config_passed,
        "training_rows_sha256": sha256_rows(fit_rows_df),
        "usable_rows_sha256": sha256_rows(data),
        "hash_rule": "SHA-256 of canonical CSV: header case_id,f,d_um,h_um,v_mm_s,mfr,pd; rows sorted "
                     "by case_id; floats as Python repr; '\\n' line ends",
        "source_path": str(source_path) if source_path else None,
        "source_sha256": hashlib.sha256(Path(source_path).read_bytes()).hexdigest() if source_path else None,
        "n_usable": int(len(data)), "n_train": n_train, "n_test": n_test, "n_fit": int(fit_mask.sum()),
        "exclusions": exclusions,
        "split": {"rule": "test iff SHA-256('<split_seed>|<case_id>')[:8]/2**64 < test_fraction",
                  "split_seed": cfg["split_seed"], "test_fraction": cfg["test_fraction"],
                  "test_case_ids": sorted(ids[te].tolist())},
        "training_ranges": {n: [float(lo), float(hi)] for n, lo, hi in zip(NAMES, low, high)},
        "range_tolerance": float(cfg["range_tolerance"]),
        "test_r2": {t: {"ensemble": ensemble_r2[t],
                        "sweep_mean": float(s_idx.loc[(t, chosen[t]), "r2_mean"]),
                        "sweep_min": float(s_idx.loc[(t, chosen[t]), "r2_min"]),
                        "sweep_max": float(s_idx.loc[(t, chosen[t]), "r2_max"])} for t in TARGETS},
        "cv_r2": {t: {"mean": float(s_idx.loc[(t, chosen[t]), "cv_r2_mean"]),
                      "std": float(s_idx.loc[(t, chosen[t]), "cv_r2_std"])} for t in TARGETS},
        "gp_test_r2": {r["target"]: r["r2_test"] for r in gp_rows},
        "parity": {r["target"]: {"slope": r["slope"], "intercept": r["intercept"]} for r in fit_rows},
        "versions": versions(),
        "notes": notes,
    }
    model = SurrogateModel(members=members, neurons=chosen, train_low=low, train_high=high,
                           range_tolerance=float(cfg["range_tolerance"]),
                           metadata=_jsonable(metadata))
    return SurrogateResult(config=cfg, config_passed=config_passed, exclusions=exclusions, split=split,
                           runs=runs, summary=summary, cv=cv, gp=gp, learning=learning, parity=parity,
                           parity_fit=parity_fit, chosen=chosen, ensemble_r2=ensemble_r2, model=model,
                           notes=notes)


def learning_curve(data: pd.DataFrame, split: pd.DataFrame, chosen: dict, cfg: dict,
                   notes: list | None = None, reuse: dict | None = None) -> pd.DataFrame:
    """Held-out R^2 against the number of cases used (prefix of ``index`` in the LDS sweep).

    ``data``: usable rows (``select_training_rows``), ``split`` aligned with it.  For each prefix
    size N the training cases are the non-test cases with ``index < N``; every N is evaluated on
    the same held-out cases (all test cases of ``data``), with the chosen neuron count, every
    seed (mean, min, max), and the GP baseline (no optimizer restarts).  ``reuse``: {"mask":
    training mask, "mlp": {(target, neurons, seed): fitted}, "gp": {target: fitted}}; the prefix
    whose training cases equal that mask takes those fits instead of refitting the same models.
    """
    cols = ["target", "n_cases", "n_train", "n_test", "r2_mean", "r2_min", "r2_max", "gp_r2"]
    notes = notes if notes is not None else []
    spec = cfg["learning_curve"]
    if spec is None:
        return pd.DataFrame(columns=cols)
    if "index" not in data.columns:
        notes.append("learning curve skipped: the table has no 'index' column")
        return pd.DataFrame(columns=cols)
    in_sweep = np.ones(len(data), bool)
    sw = cfg["learning_curve_sweep"]
    if sw is not None and "sweep" in data.columns:
        in_sweep = (data["sweep"].astype(str) == sw).to_numpy()
    if not in_sweep.any():
        notes.append(f"learning curve skipped: no usable rows of sweep {sw!r}")
        return pd.DataFrame(columns=cols)
    index = pd.to_numeric(data["index"], errors="coerce").to_numpy(float)
    sizes = _auto_sizes(int(np.nanmax(index[in_sweep])) + 1) if spec == "auto" else [int(s) for s in spec]
    is_test = split["is_test"].to_numpy()
    X = data[list(NAMES)].to_numpy(float)
    te = is_test
    reuse = reuse or {}
    items = []  # (kind, key, fitted estimator or None, job)
    for n in sizes:
        trn = in_sweep & ~is_test & (index < n)
        if trn.sum() < MIN_TRAIN:
            notes.append(f"learning curve: N = {n} skipped, only {int(trn.sum())} training cases")
            continue
        # a prefix whose training cases are exactly the main training set re-uses those fits
        same = reuse.get("mask") is not None and np.array_equal(trn, reuse["mask"])
        for t in TARGETS:
            y = data[t].to_numpy(float)
            for s in cfg["seeds"]:
                est = reuse.get("mlp", {}).get((t, chosen[t], s)) if same else None
                items.append(("mlp", (t, n, int(trn.sum()), s), est,
                              (_fit_mlp_job, (X[trn], y[trn], chosen[t], s, cfg))))
            if cfg["gp"]:
                est = reuse.get("gp", {}).get(t) if same else None
                items.append(("gp", (t, n), est, (_fit_gp_job, (X[trn], y[trn], cfg, 0))))
    todo = [i for i, it in enumerate(items) if it[2] is None]
    fitted = dict(zip(todo, (r[0] for r in _run([items[i][3] for i in todo], cfg))))
    rows, gp_r2 = [], {}
    for i, (kind, key, est, _) in enumerate(items):
        est = fitted.get(i, est)
        r2 = _r2(data[key[0]].to_numpy(float)[te], _predict(est, X[te], cfg))
        if kind == "mlp":
            t, n, ntr, s = key
            rows.append(dict(target=t, n_cases=n, n_train=ntr, seed=s, r2=r2))
        else:
            gp_r2[key] = r2
    if not rows:
        return pd.DataFrame(columns=cols)
    lc = (pd.DataFrame(rows).groupby(["target", "n_cases", "n_train"], sort=False)["r2"]
          .agg(r2_mean="mean", r2_min="min", r2_max="max").reset_index())
    lc.insert(3, "n_test", int(te.sum()))
    lc["gp_r2"] = [gp_r2.get((t, n), np.nan) for t, n in zip(lc["target"], lc["n_cases"])]
    return lc[cols]


def metrics_table(result: SurrogateResult, path: str | Path | None = None) -> pd.DataFrame:
    """R^2 per target per neuron count (mean, min, max over seeds), CV mean/std, the chosen
    ensemble and the GP baseline, one row each; written as CSV if ``path`` is given."""
    s = result.summary
    tab = pd.DataFrame(dict(
        target=s["target"], model="mlp", neurons=s["neurons"].astype(float), r2_mean=s["r2_mean"],
        r2_min=s["r2_min"], r2_max=s["r2_max"], r2_train_mean=s["r2_train_mean"],
        cv_r2_mean=s["cv_r2_mean"], cv_r2_std=s["cv_r2_std"], n_seeds=s["n_seeds"],
        n_converged=s["n_converged"], chosen=s["chosen"]))
    extra = []
    for t in TARGETS:
        st = s[(s["target"] == t) & s["chosen"]].iloc[0]
        r = result.ensemble_r2[t]
        extra.append(dict(target=t, model="mlp_ensemble", neurons=float(result.chosen[t]), r2_mean=r,
                          r2_min=r, r2_max=r, r2_train_mean=np.nan, cv_r2_mean=st["cv_r2_mean"],
                          cv_r2_std=st["cv_r2_std"], n_seeds=int(result.config["ensemble_members"]),
                          n_converged=np.nan, chosen=True))
    for _, g in result.gp.iterrows():
        extra.append(dict(target=g["target"], model="gp", neurons=np.nan, r2_mean=g["r2_test"],
                          r2_min=g["r2_test"], r2_max=g["r2_test"], r2_train_mean=np.nan,
                          cv_r2_mean=g["cv_r2_mean"], cv_r2_std=g["cv_r2_std"], n_seeds=np.nan,
                          n_converged=np.nan, chosen=False))
    tab = pd.concat([tab, pd.DataFrame(extra)], ignore_index=True)
    tab["n_train"], tab["n_test"] = result.n_train, result.n_test
    order = {t: i for i, t in enumerate(TARGETS)}
    tab = tab.sort_values(["target", "model", "neurons"], key=lambda c: c.map(order) if c.name == "target" else c,
                          kind="mergesort").reset_index(drop=True)
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        tab.to_csv(path, index=False)
    return tab


# --------------------------------------------------------------------------------------------
# save / load
# --------------------------------------------------------------------------------------------
def sidecar_path(path: str | Path) -> Path:
    path = Path(path)
    return path.with_suffix(".json") if path.suffix == ".joblib" else path.with_name(path.name + ".json")


def save_model(model: SurrogateModel, path: str | Path) -> tuple[Path, Path]:
    """joblib file of the model and a JSON sidecar of its metadata (``x.joblib`` -> ``x.json``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    joblib.dump(model, path)
    side = sidecar_path(path)
    side.write_text(json.dumps(_jsonable(model.metadata), indent=2, sort_keys=True) + "\n")
    return path, side


def load_model(path: str | Path) -> SurrogateModel:
    """Load a saved surrogate (a pickle: trusted files only).  Warns when the scikit-learn
    version differs from the training one or the sidecar disagrees with the embedded metadata."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"surrogate model file not found: {path}")
    model = joblib.load(path)
    if not isinstance(model, SurrogateModel):
        raise ValueError(f"{path} does not hold a spreadmap SurrogateModel (got {type(model).__name__})")
    saved = model.metadata.get("versions", {}).get("sklearn")
    if saved and saved != sklearn.__version__:
        warnings.warn(f"{path} was trained with scikit-learn {saved}, running {sklearn.__version__}; "
                      "predictions may differ", UserWarning, stacklevel=2)
    side = sidecar_path(path)
    if side.is_file():
        meta = json.loads(side.read_text())
        if meta.get("training_rows_sha256") != model.metadata.get("training_rows_sha256"):
            warnings.warn(f"sidecar {side} does not match the model in {path} (training hash differs)",
                          UserWarning, stacklevel=2)
    return model


# --------------------------------------------------------------------------------------------
# prediction
# --------------------------------------------------------------------------------------------
def _numeric_column(values, name: str) -> np.ndarray:
    arr = np.asarray(values)
    if arr.dtype.kind in "fiu":
        return arr.astype(float)
    for i, v in enumerate(arr.ravel()):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise ValueError(f"parameter {name!r} must be numeric; got {v!r} ({type(v).__name__}) at row {i}")
    return arr.astype(float)


def as_points(points) -> np.ndarray:
    """Validate prediction input and return an (n, 4) float array in NAMES order.

    Accepts a DataFrame or a mapping with exactly the columns NAMES (any order), or an array-like
    of shape (n, 4) / (4,) in NAMES order.  Raises ValueError naming the problem for unknown or
    missing columns, a wrong number of columns, non-numeric values, NaN/inf, or no points.
    """
    expected = ", ".join(NAMES)
    if isinstance(points, Mapping) and not isinstance(points, pd.DataFrame):
        try:
            points = pd.DataFrame({k: np.atleast_1d(np.asarray(v, dtype=object)) for k, v in points.items()})
        except ValueError as e:
            raise ValueError(f"parameter values of unequal length: {e}") from None
    if isinstance(points, pd.DataFrame):
        cols = [str(c) for c in points.columns]
        unknown = [c for c in cols if c not in NAMES]
        missing = [n for n in NAMES if n not in cols]
        if unknown:
            raise ValueError(f"unknown column(s) {unknown}; expected exactly {expected}")
        if missing:
            raise ValueError(f"missing column(s) {missing}; expected exactly {expected}")
        if len(set(cols)) != len(cols):
            raise ValueError(f"duplicate column names {cols}")
        X = np.column_stack([_numeric_column(points[n].to_numpy(), n) for n in NAMES]) if len(points) \
            else np.empty((0, len(NAMES)))
    else:
        if isinstance(points, (str, bytes)):
            raise ValueError(f"points must be numbers ({expected}), got the string {points!r}")
        try:
            arr = np.asarray(points)
            if arr.dtype.kind not in "fiu" or not isinstance(points, np.ndarray):
                # keep each value's own type: a bool or a string among numbers is refused by name
                arr = np.asarray(points, dtype=object)
        except ValueError as e:  # ragged nested lists
            raise ValueError(f"points are not a rectangular table: {e}") from None
        if arr.ndim == 1:
            arr = arr.reshape(1, -1)
        if arr.ndim != 2 or arr.shape[1] != len(NAMES):
            raise ValueError(f"points must have {len(NAMES)} columns ({expected}); got shape {arr.shape}")
        X = np.column_stack([_numeric_column(arr[:, j], n) for j, n in enumerate(NAMES)]) if len(arr) \
            else np.empty((0, len(NAMES)))
    if X.shape[0] == 0:
        raise ValueError("no points to predict")
    bad = ~np.isfinite(X)
    if bad.any():
        i, j = map(int, np.argwhere(bad)[0])
        raise ValueError(f"non-finite value {X[i, j]} for parameter {NAMES[j]!r} at row {i} "
                         f"({int(bad.sum())} non-finite value(s) in total)")
    return X


def out_of_range(model: SurrogateModel, X: np.ndarray) -> np.ndarray:
    """Boolean (n, 4): parameter outside the trained range widened by the tolerance."""
    lo, hi = model.bounds_with_tolerance()
    return (X < lo) | (X > hi)


def predict(model: SurrogateModel, points) -> pd.DataFrame:
    """Predict MFR and PD with their ensemble uncertainty.

    Returns a DataFrame with the input columns (NAMES), ``mfr``, ``mfr_std``, ``pd``, ``pd_std``,
    ``outside_training_range`` (bool) and ``outside_parameters`` (names, ';'-joined).  Points
    outside the trained range are predicted (extrapolated) but flagged, with one
    ``OutOfRangeWarning`` per offending parameter.  Malformed input raises ValueError.
    """
    if not isinstance(model, SurrogateModel):
        raise TypeError(f"model must be a SurrogateModel, got {type(model).__name__}")
    X = as_points(points)
    oor = out_of_range(model, X)
    lo, hi = model.train_low, model.train_high
    for j, name in enumerate(model.names):
        rows = np.flatnonzero(oor[:, j])
        if len(rows):
            unit = "" if BY_NAME[name].unit == "-" else f" {BY_NAME[name].unit}"
            i = int(rows[np.argmax(np.abs(X[rows, j] - (lo[j] + hi[j]) / 2))])
            warnings.warn(
                f"{len(rows)} of {len(X)} point(s) outside the trained range of {name} "
                f"[{lo[j]:.6g}, {hi[j]:.6g}]{unit} (tolerance {model.range_tolerance:g} of the span): "
                f"e.g. {name} = {X[i, j]:.6g} at row {i}; the surrogate extrapolates there, treat "
                "the prediction as unreliable", OutOfRangeWarning, stacklevel=2)
    preds = model.predict_members(X)
    out = pd.DataFrame(X, columns=list(model.names))
    for t in model.targets:
        mean, std = _ensemble_stats(preds[t])
        out[t], out[f"{t}_std"] = mean, std
    out["outside_training_range"] = oor.any(axis=1)
    out["outside_parameters"] = [";".join(n for n, b in zip(model.names, r) if b) for r in oor]
    return out


# --------------------------------------------------------------------------------------------
# command line and Snakemake entry (scripts/predict.py is a thin wrapper around these)
# --------------------------------------------------------------------------------------------
def parse_point(tokens: Sequence[str]) -> dict:
    """``["f=0.3", "d_um=30", ...]`` -> {"f": 0.3, ...}; every parameter exactly once."""
    point = {}
    for tok in tokens:
        if "=" not in tok:
            raise ValueError(f"point token {tok!r} is not NAME=VALUE (names: {', '.join(NAMES)})")
        name, _, val = tok.partition("=")
        name = name.strip()
        if name not in NAMES:
            raise ValueError(f"unknown parameter {name!r} in {tok!r}; expected {', '.join(NAMES)}")
        if name in point:
            raise ValueError(f"parameter {name!r} given twice in one point")
        try:
            x = float(val)
        except ValueError:
            raise ValueError(f"value of {name!r} is not a number: {val!r}") from None
        if not math.isfinite(x):
            raise ValueError(f"value of {name!r} is not finite: {val!r}")
        point[name] = x
    missing = [n for n in NAMES if n not in point]
    if missing:
        raise ValueError(f"point {' '.join(tokens)!r} lacks parameter(s) {missing}")
    return point


def read_points_csv(path: str | Path) -> pd.DataFrame:
    """Points from a CSV with exactly the columns NAMES (checked by ``as_points``)."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"points file not found: {path}")
    try:
        return pd.read_csv(path)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
        raise ValueError(f"cannot read points CSV {path}: {e}") from None


def predict_to_frame(model: SurrogateModel, points: pd.DataFrame, log=None) -> pd.DataFrame:
    """predict(), with every OutOfRangeWarning also written as 'warning: ...' to ``log``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", OutOfRangeWarning)
        out = predict(model, points)
    for w in caught:
        if log is not None and issubclass(w.category, OutOfRangeWarning):
            print(f"warning: {w.message}", file=log)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return out


def cli_main(argv: Sequence[str] | None = None) -> int:
    """``predict.py MODEL.joblib [--point f=.. d_um=.. h_um=.. v_mm_s=..]... [--csv P.csv] [--out O.csv]``"""
    ap = argparse.ArgumentParser(
        prog="predict.py",
        description="Predict MFR and PD (with ensemble uncertainty) from a saved spreadmap surrogate.")
    ap.add_argument("model", help="model file written by spreadmap.surrogate.save_model (.joblib)")
    ap.add_argument("--point", nargs="+", action="append", default=[], metavar="NAME=VALUE",
                    help=f"one point: {' '.join(n + '=...' for n in NAMES)} (repeatable)")
    ap.add_argument("--csv", help=f"CSV of points with the columns {', '.join(NAMES)}")
    ap.add_argument("--out", help="write the predictions to this CSV (the table is printed as well)")
    args = ap.parse_args(argv)
    try:
        if not args.point and not args.csv:
            raise ValueError("no points given: use --point NAME=VALUE ... and/or --csv FILE")
        frames = []
        if args.point:
            frames.append(pd.DataFrame([parse_point(tokens) for tokens in args.point]))
        if args.csv:
            frames.append(read_points_csv(args.csv))
        pts = pd.concat(frames, ignore_index=True) if len(frames) > 1 else frames[0]
        as_points(pts)  # refuse malformed input before loading the model
        model = load_model(args.model)
        out = predict_to_frame(model, pts, log=sys.stderr)
    except (ValueError, FileNotFoundError) as e:
        print(f"predict.py: error: {e}", file=sys.stderr)
        return 2
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        out.to_csv(args.out, index=False)
    with pd.option_context("display.max_rows", None, "display.max_columns", None, "display.width", 200):
        print(out.to_string(index=False, float_format=lambda v: f"{v:.6g}"))
    return 0


def snakemake_main(smk) -> None:
    """Entry for Snakemake's ``script:`` directive.

    input: ``model`` (or input[0]); optional ``points`` (or input[1]), a CSV of points.
    params: optional ``points``, a list of {name: value} dicts or of "NAME=VALUE ..." strings.
    output: input[0] is the predictions CSV.  Out-of-range warnings go to stderr and to log[0].
    Malformed input raises ValueError, which fails the job.
    """
    inp, params = smk.input, smk.params
    model_path = getattr(inp, "model", None) or inp[0]
    pts_csv = getattr(inp, "points", None) or (inp[1] if len(inp) > 1 else None)
    frames = []
    if pts_csv:
        frames.append(read_points_csv(pts_csv))
    p = getattr(params, "points", None)
    if p:
        frames.append(pd.DataFrame([parse_point(x.split()) if isinstance(x, str) else dict(x) for x in p]))
    if not frames:
        raise ValueError("no points: give input 'points' (CSV) or params 'points'")
    pts = pd.concat(frames, ignore_index=True)
    model = load_model(model_path)
    buf = io.StringIO()
    out = predict_to_frame(model, pts, log=buf)
    sys.stderr.write(buf.getvalue())
    if len(smk.log):
        Path(smk.log[0]).write_text(buf.getvalue())
    Path(smk.output[0]).parent.mkdir(parents=True, exist_ok=True)
    out.to_csv(smk.output[0], index=False)
