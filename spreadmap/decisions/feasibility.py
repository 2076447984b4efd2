"""Which (h, v) settings meet the user's layer bounds for a powder, with what probability, and
which of them to recommend.

What "meeting a bound" means (``about``):

* ``run`` (the default): **a new DEM run's layer** meets every bound. An engineer spreads one
  layer, not the mean of many, so the run's noise counts: for each joint posterior draw m of the
  mean functions, the chance that a run meets every bound is
  prod_t [Phi((max_t - m_t) / s_t) - Phi((min_t - m_t) / s_t)], s_t the noise SD of one run at that
  point (the surrogate's per-case noise model; the targets' noises taken as independent), and the
  probability is its average over the draws: the mean-plus-noise draws integrated over the noise
  in closed form, which carries no Monte-Carlo error from the noise.
* ``mean``: **the mean function** (what the maps draw) meets every bound: the share of draws in
  which it does. Narrower than ``run`` wherever the noise is comparable to the distance to a bound.

A powder is one value or a [low, high] range of f and d each. With a range a setting counts only
if the bounds hold for **the whole range**: in each posterior draw the worst powder of the range
(``range_points`` values per ranged parameter, ends included) decides, so the probability is that
of the bounds holding for every powder of the range (``mean``), or the expected chance of a run
meeting them with the worst powder of the range (``run``). This is why the draws must be joint
over the powders of a setting: the draws come from ``SurrogateModel.draws`` on blocks that hold
every powder of a setting together (GP posterior draws, or the MLP ensemble's members).

A setting is **beyond the data** when, for any powder of the range, it lies farther than
``maps.support.max_distance`` case spacings from every usable case or its model SD exceeds
``maps.support.max_sd_ratio`` x the noise SD of a run for a bounded or quality target (the maps'
rule, ``spreadmap.maps.grids.evaluate``). Such settings are marked and never recommended: a
setting beyond the data that would beat the recommendation is listed as ``beyond_data`` with
``recommended`` False, and a powder whose only qualifying settings are beyond the data gets no
recommendation (status ``beyond_data_only``). Bounds that no setting meets are a result, not an
error: status ``none_meets`` with the best probability found and where.

The recommendations among the settings whose probability is at least ``confidence`` and which lie
within the data: **fastest**, the highest blade speed v (ties: the higher probability, then the
better quality); **best quality**, the best posterior mean of the quality target (for a range its
worst value over the range; ties: the higher probability).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.special import ndtr
from threadpoolctl import threadpool_limits

from .. import slices
from ..design import NAMES
from ..maps import grids
from .config_section import DecisionError, powder_size, span

SETTINGS = slices.DECISIONS  # the machine's (h, v) at a powder: the one definition, spreadmap.slices
STATUSES = ("recommended", "beyond_data", "beyond_data_only", "none_meets")
BLOCK_POINTS = 400  # design points per joint draw (a GP draw factorises a matrix of this side; cost ~ side^3)


@dataclass(frozen=True)
class Powder:
    """A powder: friction and diameter (the D50 of a size distribution), each (low, high); low ==
    high is one value; the span its certificate states (None: it states none)."""

    name: str
    f: tuple
    d_um: tuple
    span: float | None = None
    size_key: str = "d_um"  # the config key that gave the size (d_um, or a certificate's d50_um)

    @property
    def ranged(self) -> bool:
        return self.f[0] != self.f[1] or self.d_um[0] != self.d_um[1]

    def points(self, n: int) -> pd.DataFrame:
        """The powders covering the range, f slowest: n values per ranged parameter, ends included;
        columns f and d_um (the powder maps' axes, ``spreadmap.slices.POWDER.varying``)."""
        fs = np.linspace(self.f[0], self.f[1], n) if self.f[0] != self.f[1] else np.array([self.f[0]])
        ds = np.linspace(self.d_um[0], self.d_um[1], n) if self.d_um[0] != self.d_um[1] else np.array([self.d_um[0]])
        f, d = np.meshgrid(fs, ds, indexing="ij")
        return pd.DataFrame({"f": f.ravel(), "d_um": d.ravel()})

    def label(self) -> str:
        def one(v, fmt):
            return format(v[0], fmt) if v[0] == v[1] else f"{format(v[0], fmt)}-{format(v[1], fmt)}"
        if self.span is None:
            return f"{self.name}: f {one(self.f, 'g')}, d {one(self.d_um, 'g')} um"
        return f"{self.name}: f {one(self.f, 'g')}, D50 {one(self.d_um, 'g')} um, span {self.span:.2f}"


def powders_from_config(dec: dict) -> list[Powder]:
    """The powders of the ``decisions:`` config, in its order.

    Parameters
    ----------
    dec : dict
        The ``decisions:`` config with defaults (``decision_config``); its ``powders`` maps a
        name to ``f`` [-] and the size (``config_section.powder_size``: ``d_um`` [um], one value or
        a [low, high] range, or a certificate's D10 / D50 / D90, or D50 and span).

    Returns
    -------
    list of Powder
        One per powder, f and d_um (the D50) as (low, high) (low == high for one value), and the
        span it states.
    """
    return [Powder(name, span(spec["f"]), *powder_size(spec), size_key="d_um" if "d_um" in spec else "d50_um")
            for name, spec in dec["powders"].items()]


def setting_grid(dec: dict) -> tuple[np.ndarray, np.ndarray]:
    """The machine's settings searched: the decisions' slice's axes (``spreadmap.slices.DECISIONS``:
    h and v over ``decisions.machine``'s limits, n_h and n_v values, ends included)."""
    axes = SETTINGS.axes(dec["machine"])
    return tuple(axes[n] for n in SETTINGS.varying)


def check_inputs(model, dec: dict, powders) -> None:
    """Refuse, naming the key, what the model cannot answer: a target it lacks, machine ranges
    outside its design space, a powder outside its design space or its data."""
    for target in dec["bounds"]:
        if target not in model.targets:
            raise DecisionError(f"config key 'decisions.bounds.{target}': the surrogate has no target {target!r} "
                                f"(its targets: {list(model.targets)})")
    if dec["quality"]["target"] not in model.targets:
        raise DecisionError(f"config key 'decisions.quality.target': the surrogate has no target "
                            f"{dec['quality']['target']!r} (its targets: {list(model.targets)})")
    low, high = np.asarray(model.design_low, float), np.asarray(model.design_high, float)
    for name in SETTINGS.varying:
        i = NAMES.index(name)
        lo, hi = dec["machine"][name]
        if lo < low[i] or hi > high[i]:
            raise DecisionError(f"config key 'decisions.machine.{name}': [{lo:g}, {hi:g}] reaches outside the "
                                f"model's design space ({name} {low[i]:g} to {high[i]:g})")
    data = np.asarray(model.train_X, float)
    tolerance = model.spacing() * (high - low)  # one median case spacing, per parameter
    for powder in powders:
        for name in slices.POWDER.varying:
            i = NAMES.index(name)
            lo, hi = getattr(powder, name)
            key = f"config key 'decisions.powders.{powder.name}.{powder.size_key if name == 'd_um' else name}'"
            if lo < low[i] or hi > high[i]:
                raise DecisionError(f"{key}: {_show(lo, hi)} lies outside the model's design space "
                                    f"({name} {low[i]:g} to {high[i]:g})")
            seen = data[:, i].min(), data[:, i].max()
            if lo < seen[0] - tolerance[i] or hi > seen[1] + tolerance[i]:
                raise DecisionError(f"{key}: {_show(lo, hi)} lies outside the model's data (its {len(data)} cases "
                                    f"span {name} {seen[0]:.3g} to {seen[1]:.3g})")


def _show(lo, hi) -> str:
    return f"{lo:g}" if lo == hi else f"[{lo:g}, {hi:g}]"


def _chance(draw: np.ndarray, noise: np.ndarray, bound: dict, about: str) -> np.ndarray:
    """Per draw and point: the chance that one target meets its bound (a 0/1 for ``mean``)."""
    lo, hi = bound.get("min", -np.inf), bound.get("max", np.inf)
    if about == "mean":
        return ((draw >= lo) & (draw <= hi)).astype(float)
    s = np.maximum(noise, 1e-300)[None, :]
    return ndtr((hi - draw) / s) - ndtr((lo - draw) / s)


def feasibility(model, powder: Powder, h, v, bounds: dict, quality: dict, support: dict, about: str = "run",
                draws: int = 512, seed: int = 0, range_points: int = 5) -> pd.DataFrame:
    """One row per setting (h slowest, then v): ``probability`` of meeting every bound (see the
    module docstring), ``beyond_data``, the worst ``data_distance`` and model-SD ratio over the
    powder range, ``quality`` (the quality target's worst posterior mean over the range) and each
    bounded target's posterior mean, lowest and highest over the range."""
    if about not in ("run", "mean"):
        raise DecisionError(f"config key 'decisions.about': {about!r} is not one of ['run', 'mean']")
    axes = dict(zip(SETTINGS.varying, (np.asarray(h, float), np.asarray(v, float))))
    powders = powder.points(range_points)
    m = len(powders)
    points = SETTINGS.frame(axes, powders)  # each setting with every powder of the range
    settings = points[list(SETTINGS.varying)].to_numpy(float)[::m]
    X = points.to_numpy(float)
    targets = list(dict.fromkeys([*bounds, quality["target"]]))
    frame = grids.evaluate(model, points, targets, support)
    ratio = np.max([frame[f"{t}_sd_ratio"] for t in targets], axis=0)
    per_block = max(1, BLOCK_POINTS // m)
    prob = np.empty(len(settings))
    for b, start in enumerate(range(0, len(settings), per_block)):
        rows = slice(start * m, min(len(settings), start + per_block) * m)
        with threadpool_limits(1):  # two BLAS threads on a busy 2-core machine spin: 40x slower here
            F = model.draws(X[rows], draws, seed=seed + b, targets=list(bounds))
        chance = np.ones_like(next(iter(F.values())))
        for t, bound in bounds.items():
            chance *= _chance(F[t], frame[f"{t}_noise_sd"].to_numpy()[rows], bound, about)
        k = chance.shape[1] // m
        prob[start:start + k] = chance.reshape(len(chance), k, m).min(axis=2).mean(axis=0)

    def per_setting(values, how):
        return getattr(np.asarray(values, float).reshape(len(settings), m), how)(axis=1)

    worst = "min" if quality["goal"] == "max" else "max"
    out = pd.DataFrame({**dict(zip(SETTINGS.varying, settings.T)), "probability": prob,
                        "beyond_data": ~per_setting(frame["supported"], "min").astype(bool),
                        "data_distance": per_setting(frame["data_distance"], "max"),
                        "sd_ratio": per_setting(ratio, "max"),
                        "quality": per_setting(frame[quality["target"]], worst)})
    for t in targets:
        out[f"{t}_mean_low"] = per_setting(frame[t], "min")
        out[f"{t}_mean_high"] = per_setting(frame[t], "max")
    return out


def _top(grid: pd.DataFrame, kind: str, goal: str) -> pd.Series:
    """The best row of ``grid`` for ``kind``: fastest (v, then probability, then quality) or
    best_quality (quality, then probability)."""
    sign = 1.0 if goal == "max" else -1.0
    if kind == "fastest":
        keys = [grid["v_mm_s"].to_numpy(), grid["probability"].to_numpy(), sign * grid["quality"].to_numpy()]
    else:
        keys = [sign * grid["quality"].to_numpy(), grid["probability"].to_numpy()]
    order = np.lexsort([k for k in reversed(keys)])  # lexsort: last key primary
    return grid.iloc[order[-1]]


def _better(a: pd.Series, b: pd.Series, kind: str, goal: str) -> bool:
    if kind == "fastest":
        return a["v_mm_s"] > b["v_mm_s"]
    return a["quality"] > b["quality"] if goal == "max" else a["quality"] < b["quality"]


def recommend(grid: pd.DataFrame, confidence: float, goal: str = "max") -> list[dict]:
    """The fastest and the best-quality rows of one powder's ``feasibility`` grid (module
    docstring), each with ``kind``, ``status`` (one of STATUSES) and ``recommended``."""
    meets = grid["probability"].to_numpy() >= confidence
    inside = ~grid["beyond_data"].to_numpy(bool)
    rows = []
    for kind in ("fastest", "best_quality"):
        if (meets & inside).any():
            best = _top(grid[meets & inside], kind, goal)
            rows.append({**best.to_dict(), "kind": kind, "status": "recommended", "recommended": True})
            beyond = meets & ~inside
            if beyond.any():
                other = _top(grid[beyond], kind, goal)
                if _better(other, best, kind, goal):
                    rows.append({**other.to_dict(), "kind": kind, "status": "beyond_data", "recommended": False})
        elif meets.any():
            rows.append({**_top(grid[meets], kind, goal).to_dict(), "kind": kind, "status": "beyond_data_only",
                         "recommended": False})
        else:
            pool = grid[inside] if inside.any() else grid
            rows.append({**pool.iloc[int(np.argmax(pool["probability"].to_numpy()))].to_dict(), "kind": kind,
                         "status": "none_meets", "recommended": False})
    return rows


def _note(row: dict, powder: Powder, confidence: float, best_inside: float, quality: dict, about: str) -> str:
    at = f"h {row['h_um']:.4g} um, v {row['v_mm_s']:.4g} mm/s"
    what = "a new run meets" if about == "run" else "the mean meets"
    kind = "fastest" if row["kind"] == "fastest" else f"best {quality['target']} ({quality['goal']})"
    if row["status"] == "recommended":
        return f"{kind}: {at}, P({what} every bound) = {row['probability']:.3f}"
    if row["status"] == "beyond_data":
        return (f"{kind} if the model is trusted beyond the data: {at}, P = {row['probability']:.3f}; "
                f"NOT recommended (data distance {row['data_distance']:.2f} spacings, model SD "
                f"{row['sd_ratio']:.2f}x the noise)")
    if row["status"] == "beyond_data_only":
        return (f"no recommendation: only settings beyond the data reach P >= {confidence:g}; the {kind} of them "
                f"is {at}, P = {row['probability']:.3f}")
    return (f"no setting meets the bounds with P >= {confidence:g}: the best probability found within the data is "
            f"{best_inside:.3f}, at {at}" if np.isfinite(best_inside) else
            f"no setting meets the bounds with P >= {confidence:g}, and the whole grid lies beyond the data; "
            f"the best probability is {row['probability']:.3f} at {at}")


def recommendations(model, dec: dict, support: dict) -> tuple[pd.DataFrame, dict]:
    """The recommendation table of every powder of ``dec`` (the ``decisions:`` config with
    defaults) and each powder's feasibility grid (name -> DataFrame).

    See the module docstring for what meeting a bound means, the powder ranges, the settings
    beyond the data and the two recommendations (fastest, best quality).

    Parameters
    ----------
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate (``load_model``): its targets, design space, cases and joint
        posterior draws are used.
    dec : dict
        The ``decisions:`` config with defaults (``decision_config``).
    support : dict
        The maps' support rule (``map_config(...)["support"]``): ``max_distance`` (case
        spacings) and ``max_sd_ratio`` (model SD over a run's noise SD).

    Returns
    -------
    table : pandas.DataFrame
        Two rows per powder (``kind`` fastest and best_quality, or more where a better setting
        lies beyond the data): ``powder``, ``kind``, ``status`` (one of STATUSES),
        ``recommended``, ``h_um`` [um], ``v_mm_s`` [mm/s], ``probability``, ``confidence``,
        ``about``, ``best_probability_in_data``, ``quality_target``, ``quality``,
        ``beyond_data``, ``data_distance``, ``sd_ratio``, the powder's range, the bounded
        targets' mean ranges and a ``note`` to read.
    grids : dict of str to pandas.DataFrame
        Each powder's ``feasibility`` grid (one row per (h, v) setting).

    Raises
    ------
    DecisionError
        If the model cannot answer the config: a bounded or quality target it lacks, machine
        ranges outside its design space, a powder outside its design space or its data.
    """
    powders = powders_from_config(dec)
    check_inputs(model, dec, powders)
    h, v = setting_grid(dec)
    rows, grids_out = [], {}
    for powder in powders:
        grid = feasibility(model, powder, h, v, dec["bounds"], dec["quality"], support, dec["about"],
                           dec["draws"], dec["seed"], dec["range_points"])
        grids_out[powder.name] = grid
        inside = grid.loc[~grid["beyond_data"], "probability"]
        best_inside = float(inside.max()) if len(inside) else float("nan")
        for row in recommend(grid, dec["confidence"], dec["quality"]["goal"]):
            rows.append({"powder": powder.name, "f_low": powder.f[0], "f_high": powder.f[1],
                         "d_um_low": powder.d_um[0], "d_um_high": powder.d_um[1], **row,
                         "confidence": dec["confidence"], "about": dec["about"],
                         "best_probability_in_data": best_inside, "quality_target": dec["quality"]["target"],
                         "note": _note(row, powder, dec["confidence"], best_inside, dec["quality"], dec["about"])})
    first = ["powder", "kind", "status", "recommended", "h_um", "v_mm_s", "probability", "confidence", "about",
             "best_probability_in_data", "quality_target", "quality", "beyond_data", "data_distance", "sd_ratio",
             "f_low", "f_high", "d_um_low", "d_um_high"]
    table = pd.DataFrame(rows)
    return table[first + [c for c in table.columns if c not in first]], grids_out
