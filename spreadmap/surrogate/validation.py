"""Repeated k-fold validation of one model on one target, and the numbers a statistician asks for.

Every case is predicted by models that never saw it, ``cv_repeats`` times (a fresh shuffle of the
folds each time). Whatever a model chooses (GP hyperparameters, the MLP's size and alpha, the
noise beyond the per-case SDs) it chooses on the training folds only: the model object is built
fresh and fitted on them. From the pooled out-of-fold predictions:

* RMSE against the observations, with a 95 % bootstrap interval over cases (a case's squared
  errors over the repeats are averaged first, so repeats do not count as new cases);
* the noise SD of a single run: the RMS of the cases' own SDs where the table has them
  (``noise_source = "measured"``), else the models' own estimate (``"model"``);
* the error of the mean function, sqrt(max(MSE - noise variance, 0)): what is left once the noise
  no model can remove is taken out;
* R^2 = 1 - MSE / var(y), its ceiling R^2_max = 1 - noise variance / var(y), and the
  noise-corrected R^2 = 1 - (MSE - noise var) / (var(y) - noise var), the share of the mean
  function's variance the model gets right; algebraically it equals R^2 / R^2_max, so one
  column holds both;
* coverage of the ``interval`` prediction intervals (model SD and noise SD of a new run) with a
  bootstrap interval over cases, and the mean interval half-width.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats
from sklearn.model_selection import KFold

from .models import make_model
from .training_rows import TrainingRows

N_BOOT = 2000


def out_of_fold(rows: TrainingRows, target: str, kind: str, cfg: dict, folds: int | None = None,
                repeats: int | None = None, subset: np.ndarray | None = None) -> pd.DataFrame:
    """Out-of-fold predictions: one row per (repeat, case): case_id, y, case_sd, mean, model_sd,
    noise_sd, run_sd, repeat, fold. ``subset``: row mask of the cases to use (default all)."""
    idx = np.flatnonzero(np.ones(len(rows), bool) if subset is None else subset)
    X, y = rows.X[idx], rows.y(target)[idx]
    sd_all = rows.sd(target)
    sd = None if sd_all is None else sd_all[idx]
    ids = rows.frame["case_id"].to_numpy()[idx]
    k = int(folds or cfg["cv_folds"])
    out = []
    for r in range(int(repeats or cfg["cv_repeats"])):
        kf = KFold(min(k, len(idx)), shuffle=True, random_state=int(cfg["seed"]) * 1000 + r)
        for j, (tr, te) in enumerate(kf.split(X)):
            model = make_model(kind, cfg).fit(X[tr], y[tr], None if sd is None else sd[tr])
            mean, msd, rsd = model.predictive(X[te])
            out.append(pd.DataFrame({
                "case_id": ids[te], "y": y[te], "case_sd": np.nan if sd is None else sd[te],
                "mean": mean, "model_sd": msd, "noise_sd": model.noise_sd(X[te]), "run_sd": rsd,
                "repeat": r, "fold": j}))
    return pd.concat(out, ignore_index=True)


def _boot_interval(values: np.ndarray, stat, seed: int, level: float = 0.95) -> tuple[float, float]:
    rng = np.random.default_rng(seed)
    n = len(values)
    b = np.array([stat(values[rng.integers(0, n, n)]) for _ in range(N_BOOT)])
    a = (1 - level) / 2
    return float(np.quantile(b, a)), float(np.quantile(b, 1 - a))


def verdict(lo: float, hi: float, null: float, above: str, below: str) -> str:
    """What an interval (lo, hi) says of a `null` value (the noise law's held-out check reads its
    intervals so too: spreadlab.noise_law.leave_one_out).

    Parameters
    ----------
    lo, hi : float
        The interval's ends.
    null : float
        The value it is read against.
    above, below : str
        The words for an interval wholly above `null` and wholly below it.

    Returns
    -------
    str
        `above`, `below`, or "consistent" when the interval contains `null`.
    """
    return above if lo > null else below if hi < null else "consistent"


def coverage_verdict(low: float, high: float, level: float) -> str:
    """What a coverage interval (low, high) says of intervals meant to hold `level`: "too wide"
    when its whole interval lies above the level (the intervals cover more than they claim),
    "too narrow" when it lies below, "consistent" when it contains the level, "unknown" when
    either end is missing."""
    if not (np.isfinite(low) and np.isfinite(high)):
        return "unknown"
    return verdict(low, high, level, "too wide", "too narrow")


def summarise(oof: pd.DataFrame, level: float, seed: int = 0) -> dict:
    """The validation numbers of one (model, target) from its out-of-fold predictions."""
    z = stats.norm.ppf(0.5 + level / 2)
    oof = oof.assign(sq=(oof["y"] - oof["mean"]) ** 2,
                     inside=(np.abs(oof["y"] - oof["mean"]) <= z * oof["run_sd"]).astype(float))
    per_case = oof.groupby("case_id", sort=False).agg(sq=("sq", "mean"), inside=("inside", "mean"),
                                                      y=("y", "first"), case_sd=("case_sd", "first"),
                                                      noise_sd=("noise_sd", "mean"))
    mse = float(per_case["sq"].mean())
    measured = per_case["case_sd"].notna().all()
    noise_var = float(np.mean(per_case["case_sd"] ** 2 if measured else per_case["noise_sd"] ** 2))
    var_y = float(per_case["y"].var(ddof=1))
    rmse_lo, rmse_hi = _boot_interval(per_case["sq"].to_numpy(), lambda s: np.sqrt(s.mean()), seed)
    cov = float(oof["inside"].mean())
    cov_lo, cov_hi = _boot_interval(per_case["inside"].to_numpy(), np.mean, seed + 1)
    r2_max = 1 - noise_var / var_y
    return {
        "n_cases": int(len(per_case)), "n_predictions": int(len(oof)),
        "repeats": int(oof["repeat"].nunique()),
        "rmse": float(np.sqrt(mse)), "rmse_low": rmse_lo, "rmse_high": rmse_hi,
        "noise_sd": float(np.sqrt(noise_var)), "noise_source": "measured" if measured else "model",
        "rmse_over_noise": float(np.sqrt(mse / noise_var)) if noise_var > 0 else np.inf,
        "mean_error_sd": float(np.sqrt(max(mse - noise_var, 0.0))),
        "y_sd": float(np.sqrt(var_y)),
        "r2": 1 - mse / var_y, "r2_max": r2_max,
        "r2_corrected": 1 - (mse - noise_var) / (var_y - noise_var) if var_y > noise_var else np.nan,
        "level": level, "coverage": cov, "coverage_low": cov_lo, "coverage_high": cov_hi,
        "half_width": float(z * oof["run_sd"].mean()),
        "coverage_verdict": coverage_verdict(cov_lo, cov_hi, level),
    }


def per_case(oof: pd.DataFrame) -> pd.DataFrame:
    """One row per case: its observation and its out-of-fold prediction averaged over repeats."""
    return oof.groupby("case_id", sort=False).agg(
        y=("y", "first"), case_sd=("case_sd", "first"), mean=("mean", "mean"),
        model_sd=("model_sd", "mean"), run_sd=("run_sd", "mean")).reset_index()


def parity_table(val: pd.DataFrame, oof: pd.DataFrame) -> pd.DataFrame:
    """The numbers of the parity figure: per target (in ``val``'s order), the map model's
    ``per_case`` table of its out-of-fold predictions, with ``target`` and ``model`` columns."""
    tables = []
    for t in dict.fromkeys(val["target"]):
        chosen = val[(val["target"] == t) & val["map_model"]].iloc[0]
        case = per_case(oof[(oof["target"] == t) & (oof["model"] == chosen["model"])])
        tables.append(case.assign(target=t, model=chosen["model"]))
    return pd.concat(tables, ignore_index=True)


def by_band(oof: pd.DataFrame, h_over_d: pd.Series, edges=(0.0, 1.5, 2.0, 3.0, np.inf), level: float = 0.95) -> pd.DataFrame:
    """The out-of-fold predictions of one (model, target) against their intervals, by band of h/d
    (``h_over_d``: per case id; a band is [edge, next edge)). Per band: cases, the RMS error, the
    RMS of the cases' own noise SDs, the RMS of the interval's SD (``run_sd``: model and noise of a
    new run) and of the model's SD alone, the mean z^2 (z = error / run_sd: 1 where the intervals
    are right, below 1 where they are wide) and the share inside the ``level`` interval."""
    z_level = stats.norm.ppf(0.5 + level / 2)
    hd = oof["case_id"].map(h_over_d)
    if hd.isna().any():
        raise ValueError(f"no h/d for the cases {sorted(oof.loc[hd.isna(), 'case_id'].unique())[:3]}...")
    labels = [f"{lo:g}-{hi:g}" if np.isfinite(hi) else f">= {lo:g}" for lo, hi in zip(edges[:-1], edges[1:])]
    band = pd.cut(hd, list(edges), right=False, labels=labels)
    z = (oof["y"] - oof["mean"]) / oof["run_sd"]
    rms = lambda s: float(np.sqrt(np.mean(np.square(s))))  # noqa: E731
    rows = []
    for label, idx in oof.groupby(band, observed=True).groups.items():
        g, zg = oof.loc[idx], z.loc[idx]
        rows.append({"h_over_d": label, "cases": int(g["case_id"].nunique()), "rmse": rms(g["y"] - g["mean"]),
                     "case_sd": rms(g["case_sd"]), "interval_sd": rms(g["run_sd"]), "model_sd": rms(g["model_sd"]),
                     "mean_z2": float(np.mean(zg ** 2)), "inside": float(np.mean(np.abs(zg) <= z_level))})
    return pd.DataFrame(rows)
