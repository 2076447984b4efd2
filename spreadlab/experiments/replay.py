"""The loop replayed without DEM: its real step code against a known truth, with the measured
noise and cost, to learn what its stop rule is worth before any CPU hour is spent.

What a replay is
----------------
``replay_one`` runs ``stepper.step`` (the code the workflow's checkpoint runs) batch after batch.
Where the workflow would run YADE, the replay draws the case from a ``World``:

* **truth**: the map model (``model.make_map_fit``, final fit) fitted on every usable published
  case of the study (docs/study: about 850 distinct `default` cases), its posterior mean for MFR
  and PD. A smooth function with the study's shape, known everywhere.
* **noise**: the noise law of the published cases: their calibrated per-case SDs (config
  ``noise_calibration``) fitted as ln SD linear in the physics inputs (``surrogate.noise_sd.CaseNoise``,
  it varies with h/d as the seed repeats do), MFR and PD drawn with correlation ``rho`` (the seed
  repeats' 0.79-0.97). Another preset scales the SD by sqrt(N_default / N_preset), N the spheres a
  window measures: max(the preset's target, the spheres of its shortest window), capped by its
  longest (``passed_spheres``; on 713 published cases the law gave N within 0.7 % of n_passed).
* **cost**: the planned-cost law (``cost.PlannedCost``) decides the modelled CPU (and so the
  budget, as in the workflow); a case's "measured" CPU scatters about it log-normally with the
  law's within-session residual SD.

Each replay runs to ``max_cases`` (or ``max_cpu_h`` modelled) whatever the stop rule says: the
acquisition does not depend on the stop, so the first step at which the rule holds is where a
run with that tolerance would have stopped, and one path answers every tolerance. At every step
the TRUE map error is measured against the truth on the same grids as the estimate (RMS over
the box, the machine plane and the powder plane; the worst grid), beside the rule's estimate.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from spreadmap import targets as registry
from spreadmap.case.scene import precision_target
from spreadmap.design import NAMES, Design, h_over_d
from spreadmap.loop import map_criteria
from spreadmap.loop.cost import PlannedCost
from spreadmap.loop.model import make_map_fit
from spreadmap.loop.stepper import step
from spreadmap.sampling import halton
from spreadmap.table import usable_cases

TARGETS = registry.names("base")  # mfr, pd


def passed_spheres(X: np.ndarray, mfr: np.ndarray, preset: Mapping, config: Mapping) -> np.ndarray:
    """Spheres a case's window measures: the preset's precision target (``case.scene.precision_target``),
    at least the spheres of its shortest window and at most those of its longest
    (MFR x h/d x width x window x 6/pi)."""
    X = np.asarray(X, float)
    hd = h_over_d(X)
    per_d = np.asarray(mfr, float) * hd * float(preset["width_d"]) * 6.0 / math.pi
    lo = per_d * float(preset["window_d"])
    target = precision_target(preset, config)
    if target is None:
        return lo
    hi = per_d * float(preset.get("window_max_d") or preset["window_d"])
    return np.clip(target, lo, np.maximum(hi, lo))


@dataclass
class World:
    """The truth, the noise law and the cost a replay draws its cases from (see the module doc)."""

    truth: dict                      # target -> fitted map model (its posterior mean is the truth)
    noise: dict                      # target -> CaseNoise-like model (sd at physical X, `default`)
    config: Mapping                  # the validated config (presets, scene, material, metrics)
    law: dict                        # the cost law (ln_a, b_particles, b_steps, residual_sd)
    rho: float = 0.9
    notes: list = field(default_factory=list)

    def true_map(self, X) -> dict:
        return {t: np.asarray(self.truth[t].predict(np.asarray(X, float)), float) for t in TARGETS}

    def noise_sd(self, X, preset: str) -> dict:
        X = np.asarray(X, float)
        sd = {t: np.asarray(self.noise[t].run_sd(X), float) for t in TARGETS}
        if preset != "default":
            mfr = self.true_map(X)["mfr"]
            ratio = np.sqrt(passed_spheres(X, mfr, self.config["presets"]["default"], self.config)
                            / passed_spheres(X, mfr, self.config["presets"][preset], self.config))
            sd = {t: s * ratio for t, s in sd.items()}
        return sd

    def cost(self, preset: str) -> PlannedCost:
        return PlannedCost(self.config, preset, self.law["ln_a"], self.law["b_particles"], self.law["b_steps"])

    def run_cases(self, X, preset: str, rng) -> pd.DataFrame:
        """The rows a results table would get for cases at X: truth + correlated noise, stated SDs,
        planned CPU with the law's scatter."""
        X = np.asarray(X, float)
        mean, sd = self.true_map(X), self.noise_sd(X, preset)
        z1 = rng.standard_normal(len(X))
        z2 = self.rho * z1 + math.sqrt(1 - self.rho**2) * rng.standard_normal(len(X))
        cpu = self.cost(preset)(X) * np.exp(float(self.law.get("residual_sd", 0.0)) * rng.standard_normal(len(X)))
        return pd.DataFrame({**{n: X[:, i] for i, n in enumerate(NAMES)}, "status": "ok", "flagged": False,
                             "mfr": mean["mfr"] + sd["mfr"] * z1, "pd": mean["pd"] + sd["pd"] * z2,
                             "mfr_sd": sd["mfr"], "pd_sd": sd["pd"], "cpu_time": cpu, "preset": preset})


def build_world(published: pd.DataFrame, config: Mapping, law: Mapping, rho: float = 0.9) -> World:
    """The truth and the noise law from the published cases (calibrated SDs, usable rows).

    The map model (``model.make_map_fit``, final fit) is fitted per target on the usable rows; its
    posterior mean is the truth and its per-case noise model (fitted on the same SDs) the noise law.

    Parameters
    ----------
    published : pandas.DataFrame
        The published cases (a results table with each case's calibrated SD, ``<t>_sd``, per
        target of ``TARGETS``); the truth is fitted on its usable rows.
    config : Mapping
        The validated config (presets, scene, material, metrics, surrogate, converge, maps).
    law : Mapping
        The planned-cost law: ``ln_a``, ``b_particles``, ``b_steps`` and ``residual_sd``
        (``spreadmap.loop.cost.fit_law``).
    rho : float, optional
        The correlation of MFR's and PD's noise in one case.

    Returns
    -------
    World
        The world, its ``notes`` saying how many usable cases it was fitted on.
    """
    fit = make_map_fit(config.get("surrogate"), final=True)
    truth, noise = {}, {}
    for t in TARGETS:
        X, y, sd = map_criteria.table_data(published, t)
        truth[t] = fit(X, y, sd)
        noise[t] = truth[t]  # its per-case noise model: CaseNoise fitted on the same SDs
    return World(truth, noise, config, dict(law), rho,
                 [f"truth and noise law fitted on {len(usable_cases(published, ['mfr']))} usable cases"])


def true_error(model_by_target: Mapping, world: World, grids: Mapping[str, np.ndarray]) -> dict:
    """Per target: RMS of (map mean - truth) over each grid, and the worst grid's."""
    out = {}
    for t in TARGETS:
        per = {}
        for name, pts in grids.items():
            diff = np.asarray(model_by_target[t].predict(pts), float) - world.true_map(pts)[t]
            per[name] = float(np.sqrt(np.mean(diff**2)))
        per["worst"] = max(per.values())
        out[t] = per
    return out


def replay_one(world: World, design: Mapping, seed: int, max_cases: int = 160,
               max_cpu_h: float | None = None, maps_cfg: Mapping | None = None) -> pd.DataFrame:
    """One replay of the loop, run to ``max_cases`` or ``max_cpu_h`` of modelled CPU. One row per step.

    The stop rule never stops it (the path goes on whatever the rule says; ``stops`` finds where each
    tolerance would have stopped it). See the module docstring.

    Parameters
    ----------
    world : World
        The truth, noise and cost the cases are drawn from (``build_world``).
    design : Mapping
        Converge settings overriding the config's (e.g. ``sampling``, ``acquisition``, ``batch``),
        ``name`` and optionally ``preset`` (default: the config's); see ``DESIGNS``.
    seed : int
        The replay's seed (its LDS start is seeded 1000 + seed).
    max_cases : int, optional
        The budget in cases.
    max_cpu_h : float or None, optional
        The budget in modelled CPU hours [h]; None: none.
    maps_cfg : Mapping or None, optional
        The config's ``maps`` section for the map grids; None: the world's config's.

    Returns
    -------
    pandas.DataFrame
        One row per step: ``design``, ``seed``, ``n``, ``cpu_h_modelled``, ``cpu_h_measured`` [h],
        ``n_lds``, ``reason``, and per target the rule's ``_estimate`` (before any margin),
        ``_cv_net``, ``_cv_rmse``, ``_cv_noise``, ``_cv_n``, ``_posterior`` (worst grid) and
        ``_posterior_<grid>``, the true error ``_true`` (worst grid) and ``_true_<grid>``, and
        ``_noise_sd`` (RMS of the cases' stated SDs).
    """
    cfg = world.config
    conv = {**dict(cfg["converge"]), **{k: v for k, v in design.items() if k not in ("name", "preset")},
            "budget": int(max_cases), "cpu_budget_h": max_cpu_h, "seed": int(seed)}
    # never stop on the criteria: the path goes to max_cases, and stops() finds where each
    # tolerance would have stopped it (the batches do not depend on the stop)
    conv["stop_on"] = ["map_error"]
    conv["map_error"] = {**dict(conv.get("map_error") or {}), "tolerance": {t: 1e-12 for t in TARGETS}, "draws": 0}
    preset = design.get("preset", cfg["preset"])
    cost = world.cost(preset)
    fit = make_map_fit(cfg.get("surrogate"), final=True)
    space = Design.from_config(cfg)  # the design space, built once
    grids = map_criteria.map_grids(maps_cfg or cfg.get("maps"), space)
    rng = np.random.default_rng([int(seed), 31])
    lds_seed = 1000 + int(seed)
    n = int(conv["start"])
    table = world.run_cases(halton(n, lds_seed, space)[list(NAMES)].to_numpy(float), preset, rng)
    prev, rows = None, []
    while True:
        models: dict = {}
        rec = step(table, len(table), conv, prev, fit=fit, ranges=space,
                   maps_cfg=maps_cfg or cfg.get("maps"), lds_seed=lds_seed, cost=cost, models_out=models)
        crit = rec["criteria"]["at_this_batch"]
        err = true_error(models, world, grids)
        row = {"design": design.get("name", "?"), "seed": int(seed), "n": rec["n"],
               "cpu_h_modelled": rec["cpu_hours_modelled"], "cpu_h_measured": rec["cpu_hours"],
               "n_lds": rec["n_lds"], "reason": rec["reason"]}
        for t in TARGETS:
            me = ((crit.get("map_error") or {}).get("targets") or {}).get(t, {})
            cv = ((crit.get("cv_rmse") or {}).get("targets") or {}).get(t, {})
            row[f"{t}_estimate"] = me.get("raw_estimate", me.get("estimate", np.nan))  # before any margin
            row[f"{t}_cv_net"] = me.get("cv_net_of_noise", np.nan)
            row[f"{t}_cv_rmse"] = cv.get("rmse", np.nan)
            row[f"{t}_cv_noise"] = cv.get("noise_sd", np.nan)
            row[f"{t}_cv_n"] = cv.get("n_scored", np.nan)
            post = me.get("posterior_rms_sd") or {}
            row[f"{t}_posterior"] = post.get("worst", np.nan)
            for g in grids:
                row[f"{t}_posterior_{g}"] = post.get(g, np.nan)
                row[f"{t}_true_{g}"] = err[t][g]
            row[f"{t}_true"] = err[t]["worst"]
            row[f"{t}_noise_sd"] = float(np.sqrt(np.mean(table[f"{t}_sd"].to_numpy(float) ** 2)))
        rows.append(row)
        if rec["stop"] or not rec["next_batch"]:
            break
        X = pd.DataFrame(rec["next_batch"])[list(NAMES)].to_numpy(float)
        table = pd.concat([table, world.run_cases(X, preset, rng)], ignore_index=True)
        prev = rec
    return pd.DataFrame(rows)


def stops(paths: pd.DataFrame, tolerance: Mapping[str, float], hold_for: int = 1,
          margin: float = 1.0, min_cases: int = 0) -> pd.DataFrame:
    """Where each replay would have stopped with this tolerance per target, its cost and its true error.

    The stop is the first step at which every target's estimate times ``margin`` is within its
    tolerance, ``hold_for`` steps in a row, with at least ``min_cases`` cases (the loop's
    ``converge.min_stop_cases``); a replay that never stops within its path is a row with
    ``stopped`` False (its last step).

    Parameters
    ----------
    paths : pandas.DataFrame
        ``replay_one``'s tables of several replays (``design``, ``seed``, ``n``,
        ``cpu_h_modelled``, ``<t>_estimate``, ``<t>_true``).
    tolerance : Mapping of str to float
        The tolerance per target (map-error units of the target).
    hold_for : int, optional
        Steps in a row the rule must hold.
    margin : float, optional
        Factor on the estimate.
    min_cases : int, optional
        The fewest cases a stop may have.

    Returns
    -------
    pandas.DataFrame
        One row per (design, seed): ``stopped``, ``n``, ``cpu_h`` [h] (modelled), per target
        ``_true`` and ``_estimate`` at the stop, and ``true_within`` (every target's true error
        within its tolerance).
    """
    out = []
    for (design, seed), p in paths.groupby(["design", "seed"], sort=True):
        p = p.sort_values("n")
        ok = np.all([margin * p[f"{t}_estimate"].to_numpy() <= tol for t, tol in tolerance.items()], axis=0)
        run = 0
        hit = None
        for i, (good, n) in enumerate(zip(ok, p["n"].to_numpy())):
            run = run + 1 if good else 0
            if run >= hold_for and n >= min_cases:
                hit = i
                break
        row = {"design": design, "seed": seed, "stopped": hit is not None}
        r = p.iloc[hit if hit is not None else len(p) - 1]
        row.update({"n": int(r["n"]), "cpu_h": float(r["cpu_h_modelled"])})
        within = True
        for t, tol in tolerance.items():
            row[f"{t}_true"] = float(r[f"{t}_true"])
            row[f"{t}_estimate"] = float(r[f"{t}_estimate"])
            within &= bool(r[f"{t}_true"] <= tol)
        row["true_within"] = within
        out.append(row)
    return pd.DataFrame(out)


def calibrate_margin(paths: pd.DataFrame, tolerances: Sequence[float], share: float = 0.9,
                     grid: Sequence[float] = tuple(np.round(np.arange(1.0, 2.51, 0.05), 2)),
                     min_cases: int = 0) -> float:
    """The smallest margin at which the stops of ``paths`` are honest at least ``share`` of the time.

    Pooled over designs and tolerances, a stop is honest when its true error is within tolerance;
    NaN if no margin on the grid does it. Calibrate on some seeds and judge on others: on the same
    replays the share is optimistic.

    Parameters
    ----------
    paths : pandas.DataFrame
        ``replay_one``'s tables of the calibration replays.
    tolerances : sequence of float
        The tolerances, each the same for every target.
    share : float, optional
        The share of honest stops asked for, in (0, 1].
    grid : sequence of float, optional
        The margins tried, in order (default 1.0 to 2.5 by 0.05).
    min_cases : int, optional
        The fewest cases a stop may have (``stops``).

    Returns
    -------
    float
        The first margin of ``grid`` that does it; NaN if none.
    """
    for m in grid:
        st = pd.concat([stops(paths, {t: tol for t in TARGETS}, margin=m, min_cases=min_cases) for tol in tolerances])
        st = st[st["stopped"]]
        if len(st) and st["true_within"].mean() >= share:
            return float(m)
    return float("nan")


def honesty(stopped: pd.DataFrame) -> pd.DataFrame:
    """Per design: replays, stops, and the share of stops whose true error is within tolerance.

    With its 95 % Clopper-Pearson interval, and the cases and modelled CPU at the stop (median and
    90th percentile).

    Parameters
    ----------
    stopped : pandas.DataFrame
        ``stops``' table.

    Returns
    -------
    pandas.DataFrame
        One row per design: ``replays``, ``stops``, ``within``, ``honest_share``, ``honest_low``,
        ``honest_high``, ``cases_median``, ``cases_p90``, ``cpu_h_median`` and ``cpu_h_p90`` [h];
        NaN where no replay stopped.
    """
    from scipy.stats import binomtest

    rows = []
    for design, s in stopped.groupby("design", sort=False):
        st = s[s["stopped"]]
        k, m = int(st["true_within"].sum()), int(len(st))
        ci = binomtest(k, m).proportion_ci(0.95, method="exact") if m else None
        rows.append({"design": design, "replays": int(len(s)), "stops": m, "within": k,
                     "honest_share": k / m if m else float("nan"),
                     "honest_low": ci.low if ci else float("nan"), "honest_high": ci.high if ci else float("nan"),
                     "cases_median": float(st["n"].median()) if m else float("nan"),
                     "cases_p90": float(st["n"].quantile(0.9)) if m else float("nan"),
                     "cpu_h_median": float(st["cpu_h"].median()) if m else float("nan"),
                     "cpu_h_p90": float(st["cpu_h"].quantile(0.9)) if m else float("nan")})
    return pd.DataFrame(rows)


DESIGNS: Sequence[dict] = (
    {"name": "lds", "sampling": "lds"},
    {"name": "active_ivr", "sampling": "active", "acquisition": "ivr"},
    {"name": "active_per_cpu", "sampling": "active", "acquisition": "ivr_per_cpu"},
    {"name": "active_per_cpu_b8", "sampling": "active", "acquisition": "ivr_per_cpu", "batch": 8},
    {"name": "active_per_cpu_fast", "sampling": "active", "acquisition": "ivr_per_cpu", "preset": "fast"},
    # issue 50, 2026-12-07: fewer cost-blind cases (the start's LDS and each batch's LDS half hold the
    # corner's dear cases); batches of 8, judged with stops from 56 cases
    {"name": "b8_all_active", "sampling": "active", "acquisition": "ivr_per_cpu", "batch": 8, "lds_share": 0.0},
    {"name": "b8_start24", "sampling": "active", "acquisition": "ivr_per_cpu", "batch": 8, "start": 24},
    {"name": "b8_start24_all_active", "sampling": "active", "acquisition": "ivr_per_cpu", "batch": 8, "start": 24,
     "lds_share": 0.0},
)
