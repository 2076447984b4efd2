"""Train and validate the surrogate on a results table.

1. The usable cases and the targets (``training_rows``, ``settings.resolve_targets``).
2. Per target, both models (GP and MLP) validated by repeated k-fold (``validation``), every choice
   inside the folds.
3. Per target, the model that draws the maps: ``surrogate.model`` (gp, mlp), or ``best`` = the
   lower pooled out-of-fold RMSE. (``best`` picks between two validated candidates on the same
   folds, so its own score is slightly optimistic; both numbers are reported.)
4. The final model of each target trained on every usable case.
5. The study's protocol on the same cases, reported beside (``study``).
6. A learning curve: the map model's cross-validated RMSE on prefixes of the LDS sequence.

Two halves, each a Snakemake rule of its own (issue 50: the maps need only the first):
``fit_map_model`` is step 4 (the map model; with ``best`` it needs step 3's choice, so it reads a
validation), ``validate_surrogate`` steps 2, 3, 5 and 6 (none of which the map model needs when
``surrogate.model`` names the model). Every fit is seeded by the config alone, so the final model
is the same whether or not the validation ran before it in the same process
(tests/surrogate/test_fit_once.py). ``fit_surrogate`` runs both, as the single rule did.
"""
from __future__ import annotations

import hashlib
import json
import platform
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..design import NAMES, bounds
from . import study_protocol, validation
from .models import make_model
from .saved_model import FORMAT, SurrogateModel
from .settings import make_config, resolve_targets
from .training_rows import TrainingRows, select

KINDS = ("gp", "mlp")


@dataclass
class SurrogateResult:
    config: dict
    rows: TrainingRows
    validation: pd.DataFrame        # one row per (target, model): summarise() numbers, map_model flag
    oof: pd.DataFrame               # out-of-fold predictions, columns of validation.out_of_fold + target, model
    study_runs: pd.DataFrame
    study_summary: pd.DataFrame
    learning: pd.DataFrame          # target, model, n_cases, rmse, rmse_low, rmse_high, noise_sd
    model: SurrogateModel
    notes: list = field(default_factory=list)


@dataclass
class SurrogateValidation:
    """``validate_surrogate``'s result: ``SurrogateResult`` without the model (``plots.plot_all`` draws it)."""

    config: dict
    rows: TrainingRows
    validation: pd.DataFrame
    oof: pd.DataFrame
    study_runs: pd.DataFrame
    study_summary: pd.DataFrame
    learning: pd.DataFrame
    chosen: dict                    # target -> the map model's kind (gp, mlp)
    notes: list = field(default_factory=list)


def _min_cases(cfg) -> int:
    return max(8, 2 * int(cfg["cv_folds"]))


def sha256_rows(frame: pd.DataFrame, targets) -> str:
    """SHA-256 of the training rows (case_id, inputs, targets; sorted by case_id; repr floats)."""
    cols = ["case_id", *NAMES, *targets]
    r = frame[cols].sort_values("case_id", kind="mergesort")
    lines = [",".join(cols)] + [",".join([str(rec[0]), *(repr(float(x)) for x in rec[1:])])
                                for rec in r.itertuples(index=False)]
    return hashlib.sha256(("\n".join(lines) + "\n").encode()).hexdigest()


def versions() -> dict:
    import joblib
    import scipy
    import sklearn

    return {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "sklearn": sklearn.__version__, "pandas": pd.__version__, "joblib": joblib.__version__}


def _clean(obj):
    return json.loads(pd.Series([obj]).to_json(orient="values"))[0] if obj is not None else None


def _usable_rows(df: pd.DataFrame, config) -> tuple[dict, list, TrainingRows]:
    """(effective config, targets, usable rows), refused when too few to validate."""
    cfg = make_config(config)
    targets = resolve_targets(cfg["targets"], df.columns)
    rows = select(df, targets)
    if len(rows) < _min_cases(cfg):
        raise ValueError(f"too few usable cases to train and validate: {len(rows)} usable "
                         f"(need >= {_min_cases(cfg)} for {cfg['cv_folds']}-fold validation); "
                         f"excluded: {rows.exclusions}")
    return cfg, targets, rows


def chosen_models(cfg: dict, targets, validation: pd.DataFrame | None = None) -> dict:
    """target -> the kind of the model that draws its maps: the config's ``model``, or with ``best``
    the validation's ``map_model`` row (``validate_surrogate``, or surrogate_metrics.csv read back).

    Parameters
    ----------
    cfg : dict
        The surrogate's effective config (``settings.make_config``).
    targets : sequence of str
        The targets modelled.
    validation : pandas.DataFrame or None, optional
        The validation table (columns target, model, map_model); needed with ``best``, and where
        given it must agree with the config's model.

    Returns
    -------
    dict
        target -> ``gp`` or ``mlp``.

    Raises
    ------
    ValueError
        If ``best`` has no validation, the validation lacks a target (or marks none, or two,
        of its models), or its choice is not the config's model.
    """
    if validation is None:
        if cfg["model"] == "best":
            raise ValueError("surrogate.model 'best' picks each target's model by its validation: the map model "
                             "needs the validation table (validate_surrogate, surrogate_metrics.csv)")
        return {t: cfg["model"] for t in targets}
    flag = validation["map_model"].astype(str).str.strip().str.lower().isin(["true", "1"])
    chosen = {}
    for t in targets:
        kinds = list(validation.loc[(validation["target"] == t) & flag, "model"].astype(str))
        if len(kinds) != 1:
            raise ValueError(f"the validation marks {len(kinds)} map models for target {t!r} (one expected): "
                             f"not this table's validation")
        chosen[t] = kinds[0]
        if cfg["model"] != "best" and chosen[t] != cfg["model"]:
            raise ValueError(f"the validation's map model of {t!r} is {chosen[t]!r}, the config's {cfg['model']!r}: "
                             f"a validation of another config")
    return chosen


def _validate_one(rows, target: str, kind: str, cfg) -> tuple[pd.DataFrame, dict]:
    """One target's and model's out-of-fold predictions and their summary (a job of
    ``validate_surrogate``; seeded by the config, so the same in any process)."""
    oof = validation.out_of_fold(rows, target, kind, cfg)
    return oof, validation.summarise(oof, float(cfg["interval"]), int(cfg["seed"]))


def validate_surrogate(df: pd.DataFrame, config=None, log=print, n_jobs: int = 1) -> SurrogateValidation:
    """The surrogate's validation on a results table: repeated k-fold of both models per target,
    the map model's choice, the study's protocol and the learning curve (steps 2, 3, 5, 6).

    Parameters
    ----------
    df : pandas.DataFrame
        The results table, with the noise SDs the cases are weighed by
        (``spreadmap.noise_law.apply.case_noise``); its usable rows are validated on.
    config : Mapping or None, optional
        The config's ``surrogate:`` section (schema defaults for what it leaves out).
    log : callable, optional
        Called with one line of text per validation.
    n_jobs : int, optional
        Processes for the k-fold validations (one job per target and model): the same numbers
        with any count (each is seeded by the config).

    Returns
    -------
    SurrogateValidation
        The effective config, the training rows, the validation table (one row per target and
        model, ``map_model`` marking the model that draws the maps), the out-of-fold predictions,
        the study protocol's runs and summary, the learning curve, the choice and notes.

    Raises
    ------
    ValueError
        On the table and config ``fit_surrogate`` refuses (schema, columns, a repeated case_id,
        too few usable cases).
    """
    cfg, targets, rows = _usable_rows(df, config)
    notes = []
    val_rows, oof_parts = [], []
    jobs = [(t, kind) for t in targets for kind in KINDS]
    if n_jobs > 1:  # a pool that ends with the call (joblib's loky keeps workers and a tracker alive)
        with ProcessPoolExecutor(max_workers=n_jobs) as pool:
            done = list(pool.map(_validate_one, *zip(*[(rows, t, kind, cfg) for t, kind in jobs])))
    else:
        done = [_validate_one(rows, t, kind, cfg) for t, kind in jobs]
    for (t, kind), (oof, s) in zip(jobs, done):
        val_rows.append({"target": t, "model": kind, **s})
        oof_parts.append(oof.assign(target=t, model=kind))
        log(f"validated {kind} on {t}: RMSE {s['rmse']:.4g} [{s['rmse_low']:.4g}, {s['rmse_high']:.4g}] "
            f"vs noise SD {s['noise_sd']:.4g} ({s['noise_source']}); coverage {s['coverage']:.3f} "
            f"[{s['coverage_low']:.3f}, {s['coverage_high']:.3f}] of {s['level']:g}: {s['coverage_verdict']}")
    val = pd.DataFrame(val_rows)
    chosen = {}
    for t in targets:
        v = val[val["target"] == t].set_index("model")
        chosen[t] = cfg["model"] if cfg["model"] != "best" else str(v["rmse"].idxmin())
    val["map_model"] = [chosen[t] == m for t, m in zip(val["target"], val["model"])]
    runs = study_protocol.run_protocol(rows, targets, cfg)
    summ = study_protocol.summary(runs)
    learning = learning_curve(rows, targets, chosen, cfg, notes)
    return SurrogateValidation(cfg, rows, val, pd.concat(oof_parts, ignore_index=True), runs, summ, learning,
                               chosen, notes)


def fit_map_model(df: pd.DataFrame, config=None, source_path=None, ranges=None, validation=None, study=None,
                  log=print) -> SurrogateModel:
    """The map model: each target's final model trained on every usable case (step 4), with its
    metadata; the validation is not run here (``validate_surrogate``).

    Parameters
    ----------
    df : pandas.DataFrame
        The results table, with the noise SDs the cases are weighed by
        (``spreadmap.noise_law.apply.case_noise``); its usable rows are trained on
        (``training_rows.select``).
    config : Mapping or None, optional
        The config's ``surrogate:`` section (schema defaults for what it leaves out).
    source_path : pathlib.Path or str or None, optional
        The table's file, recorded in the metadata with its SHA-256; None: not recorded.
    ranges : Design, mapping or None, optional
        The design space (``design.Design``, or the config's ``ranges``): the model's design space.
    validation : pandas.DataFrame or None, optional
        The validation table of the same table and config (``validate_surrogate``, or
        surrogate_metrics.csv read back): with ``model: best`` it says each target's model
        (required); where given it is recorded in the metadata (``validation``). None: the
        metadata has no ``validation``.
    study : pandas.DataFrame or None, optional
        The study protocol's summary, recorded in the metadata (``study``) where given.
    log : callable, optional
        Called with one line of text per final fit.

    Returns
    -------
    SurrogateModel
        The fitted surrogate with its metadata (``map_model``, ``final_models``, ``n_usable``,
        ``n_train``/``n_test`` of the study's one split, the training rows' SHA-256, ...).

    Raises
    ------
    ValueError
        If the config breaks the schema, a target column or a required column is missing, a
        case_id repeats, there are too few usable cases to validate (fewer than
        max(8, 2 x cv_folds)), or the validation does not say (or contradicts) the map model
        (``chosen_models``).
    """
    cfg, targets, rows = _usable_rows(df, config)
    chosen = chosen_models(cfg, targets, validation)
    X = rows.X
    models = {}
    for t in targets:
        models[t] = make_model(chosen[t], cfg, final=True).fit(X, rows.y(t), rows.sd(t))
        log(f"final {chosen[t]} model of {t} on {len(rows)} cases: {models[t].describe()}")
    train, test = study_protocol.split(len(rows), cfg)
    low, high = bounds(ranges)
    metadata = {
        "format": FORMAT, "targets": targets, "names": list(NAMES),
        "map_model": chosen, "final_models": {t: models[t].describe() for t in targets},
        "config": cfg, "n_usable": len(rows), "exclusions": rows.exclusions,
        "n_train": len(train), "n_test": len(test),  # the study's one split
        "noise_columns": {t: rows.sd(t) is not None for t in targets},
        "training_rows_sha256": sha256_rows(rows.frame, targets),
        "source_path": str(source_path) if source_path else None,
        "source_sha256": hashlib.sha256(Path(source_path).read_bytes()).hexdigest() if source_path else None,
        "design_ranges": {n: [float(a), float(b)] for n, a, b in zip(NAMES, low, high)},
        "training_ranges": {n: [float(X[:, j].min()), float(X[:, j].max())] for j, n in enumerate(NAMES)},
    }
    if validation is not None:
        metadata["validation"] = _clean(validation.to_dict("records"))
    if study is not None:
        metadata["study"] = _clean(study.to_dict("records"))
    metadata.update({"versions": versions(), "notes": []})
    return SurrogateModel(targets=tuple(targets), models=models, train_X=X, design_low=low, design_high=high,
                          metadata=metadata)


def fit_surrogate(df: pd.DataFrame, config=None, source_path=None, ranges=None, log=print) -> SurrogateResult:
    """Train and validate the surrogate on a results table (the steps of the module docstring):
    ``validate_surrogate``, then ``fit_map_model`` with that validation recorded in its metadata.

    Parameters
    ----------
    df, config, source_path, ranges : as ``fit_map_model`` takes them
        The results table (with its noise SDs), the config's ``surrogate:`` section, the table's
        file (recorded with its SHA-256) and the design space.
    log : callable, optional
        Called with one line of text per validation and final fit.

    Returns
    -------
    SurrogateResult
        The effective config, the training rows, the validation table (one row per target and
        model, ``map_model`` marking the model that draws the maps), the out-of-fold
        predictions, the study protocol's runs and summary, the learning curve, the fitted
        ``SurrogateModel`` (with its metadata) and notes.

    Raises
    ------
    ValueError
        If the config breaks the schema, a target column or a required column is missing, a
        case_id repeats, or there are too few usable cases to validate (fewer than
        max(8, 2 x cv_folds)).
    """
    v = validate_surrogate(df, config, log=log)
    model = fit_map_model(df, config, source_path=source_path, ranges=ranges, validation=v.validation,
                          study=v.study_summary, log=log)
    model.metadata["notes"] = v.notes
    return SurrogateResult(v.config, v.rows, v.validation, v.oof, v.study_runs, v.study_summary, v.learning, model,
                           v.notes)


def learning_curve(rows: TrainingRows, targets, chosen: dict, cfg: dict, notes: list) -> pd.DataFrame:
    """Cross-validated RMSE (one k-fold repeat) of each target's map model on LDS prefixes."""
    cols = ["target", "model", "n_cases", "rmse", "rmse_low", "rmse_high", "noise_sd", "noise_source"]
    frame = rows.frame
    if not cfg["learning_curve"] or "index" not in frame:
        return pd.DataFrame(columns=cols)
    # prefixes of a sequence: the LDS sweep, or the converge run in run order
    in_lds = (frame["sweep"].astype(str).isin(["lds", "converge"]).to_numpy() if "sweep" in frame
              else np.ones(len(frame), bool))
    index = pd.to_numeric(frame["index"], errors="coerce").to_numpy(float)
    n_total = int(in_lds.sum())
    sizes = sorted({s for s in (n_total // 4, n_total // 2, n_total) if s >= _min_cases(cfg)})
    out = []
    order = np.sort(index[in_lds])
    for n in sizes:
        subset = in_lds & (index <= order[n - 1])
        for t in targets:
            oof = validation.out_of_fold(rows, t, chosen[t], cfg, repeats=1, subset=subset)
            s = validation.summarise(oof, float(cfg["interval"]), int(cfg["seed"]))
            out.append({"target": t, "model": chosen[t], "n_cases": int(subset.sum()),
                        **{k: s[k] for k in cols[3:]}})
    if not out:
        notes.append(f"learning curve skipped: {n_total} LDS cases, fewer than {_min_cases(cfg)} per prefix")
    return pd.DataFrame(out, columns=cols)
