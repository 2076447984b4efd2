"""The numbers behind the maps: grids of design points evaluated on the surrogate.

Every grid point gets, per target, the mean, the model SD and the SD of a new DEM run, its
distance to the nearest usable case (in median case spacings, design ranges scaled to [0, 1]) and
whether the data support it: ``supported`` when that distance is at most ``max_distance`` and,
for every target drawn, the model SD is at most ``max_sd_ratio`` x the noise SD of one run (the
model knows the mean there better than one more run would). Outside, maps hatch or open their marks.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from .. import design, slices
from .. import targets as registry
from ..design import Design
from ..schema import checked
from ..slices import axis_values as values  # noqa: F401  (the maps' name for it)

# config `maps:` at the schema's defaults (schemas/config.schema.yaml): the maps' keyword defaults, for
# callers without a config (the workflow passes its config's values)
MAP_DEFAULTS = checked("maps")


def grid_frame(**columns) -> pd.DataFrame:
    """The full tensor grid of the given columns, the first given name varying slowest.

    Parameters
    ----------
    **columns : array_like or float
        Values of parameters of ``NAMES`` (f [-], d_um [um], h_um [um], v_mm_s [mm/s]): its
        values (a scalar for a fixed one); a parameter left out is held at its nominal value
        (``Design.nominal`` of the default design).

    Returns
    -------
    pandas.DataFrame
        One row per grid point, columns in NAMES order (the first of NAMES varying slowest).
    """
    columns = {n: columns[n] if n in columns else Design.of(None).nominal(n) for n in design.NAMES}
    mesh = np.meshgrid(*[np.atleast_1d(np.asarray(columns[n], float)) for n in design.NAMES], indexing="ij")
    return pd.DataFrame({n: m.ravel() for n, m in zip(design.NAMES, mesh)})


def evaluate(model, frame: pd.DataFrame, targets, support: dict) -> pd.DataFrame:
    """Grid points evaluated on the surrogate, with whether the data support each.

    Parameters
    ----------
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate (its ``correction``, if any, applied to the means and SDs; the
        support is judged on its own uncorrected SDs).
    frame : pandas.DataFrame
        The points: columns NAMES in physical units (``grid_frame``).
    targets : sequence of str
        The targets evaluated.
    support : dict
        The config's ``maps.support``: ``max_distance`` (median case spacings) and
        ``max_sd_ratio`` (model SD over one run's noise SD).

    Returns
    -------
    pandas.DataFrame
        `frame` with, per target, ``<t>`` (mean), ``<t>_model_sd``, ``<t>_run_sd``,
        ``<t>_noise_sd``, ``<t>_sd_ratio`` (the model's own SD over the noise SD, before any preset
        correction), in the target's unit; and ``data_distance`` and ``supported`` (the module
        docstring).
    """
    X = frame[list(design.NAMES)].to_numpy(float)
    out = frame.copy()
    # whether the data support a point is the model's own knowledge against its cases' noise: a
    # preset-to-reference factor (spreadmap.surrogate.correction) widens every SD alike and is not data
    correction = getattr(model, "correction", None)
    own = model.predict_stats(X, corrected=False) if correction is not None else model.predict_stats(X)
    stats = {t: correction.stats(t, *v) for t, v in own.items()} if correction is not None else own
    out["data_distance"] = model.data_distance(X)
    ok = out["data_distance"].to_numpy() <= float(support["max_distance"])
    for t in targets:
        mean, msd, rsd = stats[t]
        noise = np.sqrt(np.clip(rsd**2 - msd**2, 0, None))
        out[t], out[f"{t}_model_sd"], out[f"{t}_run_sd"], out[f"{t}_noise_sd"] = mean, msd, rsd, noise
        _, own_msd, own_rsd = own[t]
        out[f"{t}_sd_ratio"] = own_msd / np.maximum(np.sqrt(np.clip(own_rsd**2 - own_msd**2, 0, None)), 1e-300)
        ok &= out[f"{t}_sd_ratio"].to_numpy() <= float(support["max_sd_ratio"])
    out["supported"] = ok
    return out


def f_effect(model, targets, fixed, d: np.ndarray, f_low: float, f_high: float,
             draws: int = 200, seed: int = 0) -> pd.DataFrame:
    """Per d: the change of each target from f_low to f_high, with its 95 % interval and P(change > 0).

    The change is read on the mean function; its interval and probability from joint draws (both
    ends of the change in the same draw). The points are the powder maps' slice
    (``spreadmap.slices.POWDER``) at each friction.

    Parameters
    ----------
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate.
    targets : sequence of str
        The targets.
    fixed : Mapping
        The slice's fixed axes (layer thickness ``h_um`` [um], blade speed ``v_mm_s`` [mm/s]);
        an axis left out at its nominal value.
    d : numpy.ndarray
        Particle diameters [um], shape (n,).
    f_low, f_high : float
        The two friction coefficients [-].
    draws : int, optional
        Joint draws of the model.
    seed : int, optional
        Seed of the draws.

    Returns
    -------
    pandas.DataFrame
        One row per d: ``d_um`` and per target ``<t>_change``, ``<t>_change_low``,
        ``<t>_change_high`` (2.5 and 97.5 % of the draws) and ``<t>_p_increase``.
    """
    X = np.vstack([slices.POWDER.frame({"f": [f], "d_um": d}, fixed).to_numpy(float) for f in (f_low, f_high)])
    F = model.draws(X, draws, seed=seed, targets=list(targets))
    mean = model.predict_stats(X)
    rows = {"d_um": d}
    for t in targets:
        diff = F[t][:, len(d):] - F[t][:, :len(d)]
        rows[f"{t}_change"] = mean[t][0][len(d):] - mean[t][0][:len(d)]
        rows[f"{t}_change_low"] = np.quantile(diff, 0.025, axis=0)
        rows[f"{t}_change_high"] = np.quantile(diff, 0.975, axis=0)
        rows[f"{t}_p_increase"] = np.mean(diff > 0, axis=0)
    return pd.DataFrame(rows)


REGIME_TARGETS = ("mfr", "coverage", "thickness_ratio")  # what metrics.classify reads


def regime_probabilities(frame: pd.DataFrame, rules: dict) -> pd.DataFrame:
    """Probability that a new DEM run at each point falls in each regime.

    ``metrics.classify``'s rule (jamming if MFR < jam_mfr_max, else short feed if coverage or
    thickness / h is below its threshold) applied to the predictive normal of each target (model
    and noise, ``<t>_run_sd``), by ``metrics.regime_probabilities`` (the targets' errors taken as
    independent).

    Parameters
    ----------
    frame : pandas.DataFrame
        ``evaluate``'s table for ``REGIME_TARGETS``: ``mfr``, ``coverage``, ``thickness_ratio``
        and their ``_run_sd``.
    rules : dict
        The config's ``regime`` thresholds (``jam_mfr_max``, ``short_feed_coverage_min``,
        ``short_feed_thickness_min``).

    Returns
    -------
    pandas.DataFrame
        `frame` with ``p_jamming``, ``p_short_feed`` and ``p_normal`` (summing to 1).
    """
    from ..metrics import regime_probabilities as probabilities

    p = probabilities(frame["mfr"], frame["mfr_run_sd"], frame["coverage"], frame["coverage_run_sd"],
                      frame["thickness_ratio"], frame["thickness_ratio_run_sd"], rules)
    out = frame.copy()
    out["p_jamming"], out["p_short_feed"], out["p_normal"] = p["jamming"], p["short_feed"], p["normal"]
    return out


def choose_machine_y(cases: pd.DataFrame, targets) -> tuple[str, pd.DataFrame]:
    """The machine map's y axis: of the layer-quality targets present, the one carrying most
    information beyond MFR, else PD.

    Score: the variance of the target left after a straight-line fit on MFR, over its noise
    variance where the table gives ``<t>_sd`` (signal beyond MFR against noise), else the
    unexplained share 1 - r^2. The table gives each candidate's Pearson r with MFR across the cases
    and its 95 % interval (scipy), so the map can say how far y is from MFR in disguise.

    Parameters
    ----------
    cases : pandas.DataFrame
        The usable cases: ``mfr``, the candidates and, where known, their ``<t>_sd``.
    targets : iterable of str
        The candidates (the surrogate's targets); PD is scored too when given, for comparison.

    Returns
    -------
    y : str
        The chosen target (``pd`` when no layer-quality target scores).
    scores : pandas.DataFrame
        One row per scored candidate: ``target``, ``score``, ``how`` (which score), ``n`` (cases),
        ``r_with_mfr`` with ``r_low`` and ``r_high``.
    """
    cands = [t for t in (*registry.names("layer"), "pd") if t in targets and t in cases]
    rows = []
    for t in cands:
        ok = np.isfinite(cases[t].to_numpy(float)) & np.isfinite(cases["mfr"].to_numpy(float))
        y, x = cases.loc[ok, t].to_numpy(float), cases.loc[ok, "mfr"].to_numpy(float)
        if len(y) < 3 or np.ptp(x) == 0:
            continue
        resid = y - np.polyval(np.polyfit(x, y, 1), x)
        pearson = stats.pearsonr(x, y)
        ci = pearson.confidence_interval(0.95) if len(y) > 3 else (np.nan, np.nan)
        sd_col = registry.REGISTRY[t].sd_column
        if sd_col in cases and np.isfinite(cases.loc[ok, sd_col].to_numpy(float)).all():
            score, how = resid.var(ddof=2) / np.mean(cases.loc[ok, sd_col].to_numpy(float) ** 2), "residual / noise variance"
        else:
            score, how = resid.var(ddof=2) / y.var(ddof=1), "1 - r^2"
        rows.append({"target": t, "score": float(score), "how": how, "n": int(ok.sum()),
                     "r_with_mfr": float(pearson.statistic), "r_low": float(ci[0]), "r_high": float(ci[1])})
    table = pd.DataFrame(rows, columns=["target", "score", "how", "n", "r_with_mfr", "r_low", "r_high"])
    layer = table[table["target"] != "pd"]
    if layer.empty:
        return "pd", table
    return str(layer.loc[layer["score"].idxmax(), "target"]), table


def machine_y_axis(cases: pd.DataFrame, targets, y: str = "auto") -> tuple[str, str | None, pd.DataFrame]:
    """The machine map's y axis as config ``maps.machine.y`` asks, with the note the map writes on it.

    Shared by every machine map of a run (the map model's and the MLP's beside it), so both draw
    the same y.

    Parameters
    ----------
    cases : pandas.DataFrame
        The usable cases (``choose_machine_y``).
    targets : iterable of str
        The surrogate's targets.
    y : str, optional
        ``auto`` (``choose_machine_y``'s choice) or a target of the surrogate.

    Returns
    -------
    y : str
        The target on the y axis.
    note : str or None
        y's Pearson r with MFR over the usable cases with its 95 % interval (how far y is from MFR
        in disguise); None where y was not scored.
    scores : pandas.DataFrame
        ``choose_machine_y``'s table of the candidates.

    Raises
    ------
    ValueError
        If `y` names a target the surrogate does not model.
    """
    targets = list(targets)
    auto_y, scores = choose_machine_y(cases, targets)
    if y == "auto":
        y = auto_y
    elif y not in targets:
        raise ValueError(f"maps.machine.y: {y!r} is not a target of the surrogate ({targets})")
    chosen = scores.set_index("target").loc[y] if y in set(scores["target"]) else None
    note = (None if chosen is None else f"{y} against MFR over the {int(chosen['n'])} usable cases: Pearson r = "
            f"{chosen['r_with_mfr']:.2f} [{chosen['r_low']:.2f}, {chosen['r_high']:.2f}] (95 %)")
    return y, note, scores
