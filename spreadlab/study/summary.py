"""docs/study/summary.md: the study's questions answered from its published files, each number
with its interval, and "not yet" where a part has not run.

Reads (all optional): config.yaml (the floor the cases ran on, named under the title),
progress.csv, converge/stopped.json (or, while the loop runs, its last
converge/steps/step_*.json), convergence/summary.json,
surrogate/surrogate_metrics.csv, surrogate/surrogate_r2_vs_neurons.csv,
maps/sensitivity_ranking_table.csv, heldout/score.json and heldout/score.csv (the held-out
check: tools/heldout.py score) and the cases tables (the regimes, the flagged cases). The trends
are computed apart (``trends``, from surrogate/model.joblib) and handed to ``summary_markdown``,
which writes no file.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import qmc

from spreadmap.case.substrate import floor_label
from spreadmap.config import renamed_sections
from spreadmap.design import NAMES, Design
from spreadmap.design import h_over_d as gap_ratio
from spreadmap.loop.stepper import step_number
from spreadmap.surrogate.validation import by_band
from spreadmap.table import flagged, partition, usable
from spreadmap.targets import names as target_names

NOT_YET = "not yet run"


def main_effect(model, ranges: dict | None, variable: str, levels, n_base: int = 64, n_draws: int = 64,
                seed: int = 0) -> pd.DataFrame:
    """Partial dependence of each target on `variable` ("f", "v_mm_s" or "h_over_d"): at each level
    the mean prediction over a scrambled Sobol' sample of the other parameters, with a 95 % band
    from the model's draws of the mean function (the same draw for every point of a level). For
    h/d the sample's d sets h = level x d, and only points whose h lies in its range count
    (`n_points`): an effect over the part of the design space where that h/d exists."""
    design = Design.of(ranges)
    gap = design.ranges["h_um"]
    base = pd.DataFrame(qmc.scale(qmc.Sobol(d=len(NAMES), scramble=True, seed=seed).random(n_base), *design.bounds()),
                        columns=list(NAMES))
    rows = []
    for level in levels:
        X = base.copy()
        if variable == "h_over_d":
            X["h_um"] = level * X["d_um"]
            X = X[(X["h_um"] >= gap["min"]) & (X["h_um"] <= gap["max"])]
        else:
            X[variable] = level
        row = {"variable": variable, "level": float(level), "n_points": len(X)}
        if len(X):
            for target, draws in model.draws(X.to_numpy(float), n_draws, seed=seed).items():
                averages = np.asarray(draws).mean(axis=1)
                row[target] = float(averages.mean())
                row[f"{target}_low"], row[f"{target}_high"] = (float(q) for q in np.quantile(averages, [0.025, 0.975]))
        rows.append(row)
    return pd.DataFrame(rows)


def _read_csv(path: Path) -> pd.DataFrame | None:
    return pd.read_csv(path) if path.exists() else None


def _cases(study: Path) -> list[str]:
    lines = ["## Cases and CPU"]
    progress = _read_csv(study / "progress.csv")
    if progress is None:
        return lines + [NOT_YET]
    for r in progress.to_dict("records"):
        lines.append(f"- {r['sweep']}: {r['finished']} of {r['planned']} cases finished ({r['failed']} failed), "
                     f"{r['cpu_hours']:.2f} CPU hours")
    return lines


def _convergence(study: Path) -> list[str]:
    lines = ["## How many cases convergence took"]
    stopped = study / "converge" / "stopped.json"
    if stopped.exists():
        s = json.loads(stopped.read_text())
        verdict = (f"the map criteria held at **{s['n']} cases**" if s["criteria"].get("criteria_met")
                   else f"the map criteria **did not hold within {s['n']} cases** (stopped: {s['reason']})")
        lines.append(f"- The main job's loop: {verdict}; {s['usable']} usable, {s['cpu_hours']:.2f} CPU hours.")
    else:
        steps = sorted((study / "converge" / "steps").glob("step_*.json"), key=step_number)
        if steps:
            last = json.loads(steps[-1].read_text())
            lines.append(f"- The main job's loop, still running: {len(steps)} steps so far; the last one says")
            lines += ["", "```", last["summary"], "```", ""]
        else:
            lines.append(f"- The main job's loop: {NOT_YET}.")
    lines += _study_rule(study)
    rule = study / "convergence" / "summary.json"
    if rule.exists():  # the workflow's own verdicts, once both sweeps have run: what they add
        r = json.loads(rule.read_text())
        for name, v in r["sweeps"].items():
            lines.append(f"- The study's rule (five statistics within {100 * r['tolerance']:g} %), {name}: "
                         f"{v['status']} ({v['cases_run']} cases run).")
        for key, ratio in r.items():
            if key.startswith("ratio_") and isinstance(ratio, dict):
                lines.append(f"- The workflow's convergence summary: {ratio.get('text', '')}")
        stable = r.get("lds_case_by_case") or {}
        if stable.get("n_last"):
            lines.append("- The study's rule case by case on the LDS (each case against the one before): "
                         + (f"holds from N = {stable['stable_from']} on" if stable.get("stable_from")
                            else f"does not hold for good within {stable['n_last']} cases")
                         + (f" (first holds at N = {stable['first_holds']})." if stable.get("first_holds") else "."))
    return lines


def _study_rule(study: Path) -> list[str]:
    """The study's rule on the sweeps' partitions that have finished, from the published cases:
    the LDS partitions of config.yaml whose every case has run, the lattices whose every case has
    run; the largest relative change of the five statistics of MFR and PD from the partition
    before."""
    from spreadmap.study_rule.rule import DEFAULT_TOLERANCE, convergence_table, first_converged

    cfg = renamed_sections(_read_yaml(study / "config.yaml"))  # a published config may say `convergence:`
    conv = cfg.get("study_rule") or {}
    # a published config (not validated: it may predate the schema) without a tolerance ran the schema's
    tol, floors = conv.get("tolerance", DEFAULT_TOLERANCE), conv.get("floors")
    lines = []
    lds = _read_csv(study / "cases_lds.csv")
    partitions = ((cfg.get("sweeps") or {}).get("lds") or {}).get("partitions", [])
    complete = []  # the LDS partitions whose every case has run
    if lds is not None and len(lds) and "index" in lds:
        indices = set(lds["index"].astype(int))
        complete = [n for n in sorted(partitions) if all(i in indices for i in range(n))]
        if len(complete) >= 2:
            table = convergence_table(partition(lds, max(complete), sweep=None), target_names("base"), complete,
                                      tolerance=tol, floors=floors)
            steps = ", ".join(f"{int(r['partition'])}: {100 * r['max_change']:.1f} %" for r in table.to_dict("records")[1:])
            hit = first_converged(table)
            lines.append(f"- The study's rule (five statistics of MFR and PD within {100 * tol:g} % of the partition "
                         f"before), on the LDS: largest change at N = {steps}; "
                         + (f"**holds at N = {hit}**." if hit else f"**not within {max(complete)} cases**."))
    lattice = _read_csv(study / "cases_lattice.csv")
    ks = sorted(set(((cfg.get("sweeps") or {}).get("lattice") or {}).get("k", [])))
    if lattice is not None and len(lattice) and "k" in lattice:
        done = [k for k in ks if (lattice["k"] == k).sum() == k ** len(NAMES)]
        if len(done) >= 2:
            table = convergence_table(lattice[lattice["k"].isin(done)], target_names("base"), tolerance=tol, floors=floors,
                                      partition_col="k")
            steps = ", ".join(f"{int(r['partition'])}: {100 * r['max_change']:.1f} %" for r in table.to_dict("records")[1:])
            hit = first_converged(table)
            lines.append(f"- The study's rule on the lattices: largest change at N = {steps}; "
                         + (f"**holds at N = {hit}**." if hit else f"**not within {max(k ** len(NAMES) for k in done)} cases**."))
    lines += _matched_sizes(lds, lattice, ks, complete, floors)
    return lines or [f"- The study's rule on the sweeps: {NOT_YET} (fewer than two complete partitions)."]


def _matched_sizes(lds, lattice, ks, complete, floors) -> list[str]:
    """The sampling comparison at matched size, as far as the sweeps have run: each complete
    lattice k^4 and the LDS's first k^4 cases, both against the largest complete LDS partition
    (`complete`: the LDS partitions whose every case has run; the largest sample), by the study's
    change measure (spreadmap.study_rule.rule.difference_from)."""
    from spreadmap.study_rule.rule import difference_from

    if not complete or lattice is None or not len(lattice) or "k" not in lattice:
        return []
    lines = []
    for k in ks:
        n = k ** len(NAMES)
        if (lattice["k"] == k).sum() != n or max(complete) < n:
            continue
        ref = partition(lds, max(complete), sweep=None)
        of_lds = difference_from(ref, partition(lds, n, sweep=None), floors=floors).set_index(["target", "statistic"], drop=False)
        of_lattice = (difference_from(ref, lattice[lattice["k"] == k], floors=floors)
                      .set_index(["target", "statistic"], drop=False))
        parts = []
        # at the largest LDS partition's own size the LDS prefix is the reference itself: the lattice alone
        prefix = n < max(complete)
        samples = ([(f"LDS's first {n}", of_lds)] if prefix else []) + [(f"{k}^{len(NAMES)} lattice", of_lattice)]
        for name, diff in samples:
            worst = diff.loc[diff["difference"].idxmax()]
            parts.append(f"the {name} by at most {100 * worst['difference']:.1f} % ({worst['target']} {worst['statistic']}: "
                         f"{worst['other']:.4g} against {worst['reference']:.4g})")
        names = ([f"LDS {n}"] if prefix else []) + ["lattice", f"LDS {max(complete)}"]
        means = {t: ([of_lds.loc[(t, "mean"), "other"]] if prefix else [])
                 + [of_lattice.loc[(t, "mean"), "other"], of_lds.loc[(t, "mean"), "reference"]] for t in target_names("base")}
        scatter = {t: of_lds.loc[(t, "std"), "reference"] / np.sqrt(n) for t in target_names("base")}
        lines.append(f"- Matched size N = {n}, against LDS {max(complete)} (the largest sample): the five statistics of "
                     + " and of ".join(parts) + "; mean MFR " + ", ".join(f"{v:.4f}" for v in means["mfr"])
                     + " and PD " + ", ".join(f"{v:.4f}" for v in means["pd"]) + f" ({', '.join(names)}; "
                     f"the mean of {n} random cases would scatter by {scatter['mfr']:.4f} and {scatter['pd']:.4f}, "
                     f"the SD of LDS {max(complete)} over sqrt({n}))")
    return lines


def _verdict_words(low: float, high: float, level: float) -> str:
    """The coverage interval's verdict as the summary says it (surrogate.validation.coverage_verdict)."""
    from spreadmap.surrogate.validation import coverage_verdict

    words = {"too wide": f"the intervals are too wide (their coverage's CI lies above {100 * level:g} %)",
             "too narrow": f"the intervals are too narrow (their coverage's CI lies below {100 * level:g} %)",
             "consistent": f"consistent with {100 * level:g} %", "unknown": "coverage interval unknown"}
    return words[coverage_verdict(float(low), float(high), float(level))]


def _sd_verdict(r: dict, alpha: float = 0.05) -> str:
    """What the held-out z^2 test says of the stated SDs, at level alpha (one-sided each way)."""
    if float(r.get("p_sd_too_wide", float("nan"))) < alpha:
        return f"the stated SDs are too large (intervals too wide; p < {alpha:g})"
    if float(r.get("p_sd_right", float("nan"))) < alpha:
        return f"the stated SDs are too small (intervals too narrow; p < {alpha:g})"
    return f"the stated SDs are consistent (neither p < {alpha:g})"


def _surrogate(study: Path) -> list[str]:
    lines = ["## The surrogate against the noise"]
    metrics = _read_csv(study / "surrogate" / "surrogate_metrics.csv")
    if metrics is None:
        return lines + [NOT_YET]
    for r in metrics.to_dict("records"):
        lines.append(f"- {r['target']} ({r['model']}{', the maps' if r.get('map_model') else ''}): CV RMSE "
                     f"{r['rmse']:.4f} (interval {r['rmse_low']:.4f}-{r['rmse_high']:.4f}) = {r['rmse_over_noise']:.2f}x "
                     f"the noise SD {r['noise_sd']:.4f}; {100 * r['level']:g} % intervals cover "
                     f"{100 * r['coverage']:.0f} % ({100 * r['coverage_low']:.0f}-{100 * r['coverage_high']:.0f} %) "
                     f"of {r['n_predictions']} predictions of {r['n_cases']} cases: "
                     f"{_verdict_words(r['coverage_low'], r['coverage_high'], r['level'])}")
    lines += _intervals_by_band(study, metrics)
    mlp = _read_csv(study / "surrogate" / "surrogate_r2_vs_neurons.csv")
    if mlp is not None:
        for r in mlp[mlp["chosen"]].to_dict("records"):
            lines.append(f"- The study's MLP protocol, {r['target']}: R^2 {r['r2_mean']:.2f} on its 20 % test share "
                         f"(range {r['r2_min']:.2f} to {r['r2_max']:.2f} over {r['n_seeds']} seeds) at {r['neurons']} "
                         f"neurons, trained on {r['n_train']} cases (train R^2 {r['r2_train_mean']:.2f})")
    return lines


def _intervals_by_band(study: Path, metrics: pd.DataFrame) -> list[str]:
    """The maps' model's out-of-fold intervals by band of h/d (spreadmap.surrogate.validation.by_band),
    for MFR and PD, from the parity table and the h/d of the published cases tables."""
    parity = _read_csv(study / "surrogate" / "surrogate_parity.csv")
    tables = [t for t in (_read_csv(p) for p in sorted(study.glob("cases_*.csv"))) if t is not None and len(t)]
    map_model = metrics.loc[metrics["map_model"].astype(bool), "model"] if "map_model" in metrics else pd.Series([], dtype=object)
    if parity is None or not tables or map_model.empty:
        return []
    cases = pd.concat([t[["case_id", "h_um", "d_um"]] for t in tables if {"case_id", "h_um", "d_um"} <= set(t.columns)])
    h_over_d = pd.Series(gap_ratio(cases), index=cases.index).groupby(cases["case_id"]).first()
    lines = []
    for target in target_names("base"):
        oof = parity[(parity["model"] == map_model.iloc[0]) & (parity["target"] == target)]
        known = oof["case_id"].isin(h_over_d.index)
        if not known.any():
            continue
        left_out = oof.loc[~known, "case_id"].nunique()
        bands = by_band(oof[known], h_over_d)
        lines.append(f"- {target} ({map_model.iloc[0]}), its intervals by h/d (out of fold; z = error / the interval's SD, "
                     f"mean z^2 1 where they are right, below 1 where wide"
                     + (f"; {left_out} cases in no published table left out" if left_out else "") + "): " + "; ".join(
                         f"{r['h_over_d']}: {r['cases']} cases, error {r['rmse']:.4f} against the cases' noise "
                         f"{r['case_sd']:.4f}, interval SD {r['interval_sd']:.4f} (the model's {r['model_sd']:.4f}), "
                         f"mean z^2 {r['mean_z2']:.2f}, {100 * r['inside']:.0f} % inside" for r in bands.to_dict("records")))
    return lines


def _heldout(study: Path) -> list[str]:
    """The held-out check (heldout/: of the loop's surrogate as it stopped) and, where it exists, the
    second one (heldout2/: of the shipped surrogate, re-fitted with both noise calibration bands),
    each predicted before its points ran."""
    lines = ["## The held-out check (points no sweep ran, predicted before they ran)"]
    first = _heldout_score(study / "heldout")
    if first is None:
        return lines + [NOT_YET]
    lines += first
    if (study / "heldout2").is_dir():
        second = _heldout_score(study / "heldout2")
        lines.append("- The second check, of the shipped surrogate (both noise calibration bands; `heldout2/`, its "
                     "points at least 0.15 of the unit cube from every case before):")
        lines += ["  " + line for line in (second if second is not None else [f"- {NOT_YET}"])]
    return lines


def _heldout_score(folder: Path) -> list[str] | None:
    """One held-out check's lines from its score.json and score.csv; None before it is scored."""
    path = folder / "score.json"
    if not path.exists():
        return None
    lines = []
    for r in json.loads(path.read_text()):
        lines.append(f"- {r['target']}: {r['inside']} of {r['points']} points' seed means inside their "
                     f"{100 * r['level']:g} % prediction intervals (coverage {r['coverage']:.2f}, 95 % CI "
                     f"{r['coverage_low']:.2f}-{r['coverage_high']:.2f}: "
                     f"{_verdict_words(r['coverage_low'], r['coverage_high'], r['level'])}); RMSE {r['rmse']:.4f} against "
                     f"{r['rmse_expected']:.4f} expected from the stated SDs (mean z^2 {r['mean_z2']:.2f}, "
                     f"p = {r['p_sd_right']:.2g} for 'the SDs are too small', "
                     f"{r.get('p_sd_too_wide', float('nan')):.2g} for 'too large'): {_sd_verdict(r)}")
    table = _read_csv(folder / "score.csv")
    if table is not None and "inside" in table:
        outside = table[~table["inside"].astype(bool)]
        for r in outside.to_dict("records"):
            lines.append(f"  - outside: {r['name']} {r['target']}: {r['seed_mean']:.4f} over {int(r['n_runs'])} seeds "
                         f"against {r['predicted']:.4f} +- {r['sd_of_mean']:.4f} (z = {r['z']:.1f})")
    return lines


def _ranking(study: Path) -> list[str]:
    lines = ["## Which parameters matter (Sobol' total indices: of the surrogate's mean, with the 95 % interval "
             "over its draws; ranks from the intervals)"]
    table = _read_csv(study / "maps" / "sensitivity_ranking_table.csv")
    if table is None:
        return lines + [NOT_YET]
    for target, t in table.groupby("target", sort=False):
        t = t.sort_values("ST", ascending=False)
        parts = [f"{r['parameter']} {r['ST']:.2f} ({r['ST_low']:.2f}-{r['ST_high']:.2f}, rank {r['rank_ST']})"
                 for r in t.to_dict("records")]
        tied = sorted({r["rank_ST"] for r in t.to_dict("records") if "-" in str(r["rank_ST"])})
        note = f"; intervals do not separate the ranks {', '.join(tied)}" if tied else ""
        lines.append(f"- {target}: " + ", ".join(parts) + note)
    return lines


def trends(study: Path | str, ranges: dict | None = None) -> dict[str, pd.DataFrame]:
    """The study's trends: the partial dependence of every target of its surrogate, by variable.

    The partial dependence (``main_effect``) of every target of the study's surrogate
    (surrogate/model.joblib) on blade speed and friction (5 levels each over their ranges) and on
    h/d (6 levels, geometric, over what the ranges allow); empty before the surrogate exists.
    tools/publish_study.py writes each as trend_<variable>.csv.

    Parameters
    ----------
    study : pathlib.Path or str
        The study folder (docs/study).
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.

    Returns
    -------
    dict of str to pandas.DataFrame
        ``v_mm_s``, ``f`` and ``h_over_d`` -> ``main_effect``'s table: ``variable``, ``level``,
        ``n_points`` and per target its mean with ``_low`` and ``_high`` (95 % band); {} without
        the surrogate.
    """
    path = Path(study) / "surrogate" / "model.joblib"
    if not path.exists():
        return {}
    from spreadmap.surrogate.saved_model import load_model

    model = load_model(path)
    design = Design.of(ranges)
    h, d = design.ranges["h_um"], design.ranges["d_um"]
    grids = {"v_mm_s": design.axis("v_mm_s", 5), "f": design.axis("f", 5),
             "h_over_d": np.geomspace(h["min"] / d["max"], h["max"] / d["min"], 6)}
    return {variable: main_effect(model, ranges, variable, levels) for variable, levels in grids.items()}


def _trends(effects: dict[str, pd.DataFrame]) -> list[str]:
    lines = ["## How the targets change with blade speed, h/d and friction (partial dependence, 95 % bands)"]
    if not effects:
        return lines + [NOT_YET]
    for variable, effect in effects.items():
        for target in (c for c in effect.columns if f"{c}_low" in effect.columns):  # the model's targets, in order
            ends = effect.dropna(subset=[target]).iloc[[0, -1]]
            a, b = ends.to_dict("records")
            lines.append(f"- {target} vs {variable}: {a[target]:.3f} ({a[target + '_low']:.3f}-{a[target + '_high']:.3f}) "
                         f"at {a['level']:.3g} to {b[target]:.3f} ({b[target + '_low']:.3f}-{b[target + '_high']:.3f}) "
                         f"at {b['level']:.3g}")
    return lines


def _regimes(study: Path) -> list[str]:
    lines = ["## Where the regimes lie (the cases run)"]
    tables = [t for t in (_read_csv(study / f"cases_{n}.csv") for n in ("lds", "lattice", "converge")) if t is not None]
    if not tables:
        return lines + [NOT_YET]
    cases = pd.concat(tables, ignore_index=True).drop_duplicates("case_id")
    cases = cases[cases["status"] == "ok"]
    cases = cases.assign(h_over_d=gap_ratio(cases))
    for regime, group in cases.groupby("regime"):
        lines.append(f"- {regime}: {len(group)} of {len(cases)} cases; h/d {group['h_over_d'].min():.2f}-"
                     f"{group['h_over_d'].max():.2f}, v {group['v_mm_s'].min():.1f}-{group['v_mm_s'].max():.1f} mm/s")
    if "jamming" not in set(cases["regime"]) and "mfr" in cases and len(cases):
        # a regime the cases never reached is an answer too: how far the nearest case was from it
        fit = cases[usable(cases)]
        low = fit.loc[fit["mfr"].idxmin()]
        rule = (_read_yaml(study / "config.yaml").get("regime") or {}).get("jam_mfr_max")
        where = f"h/d {low['h_over_d']:.2f}, v {low['v_mm_s']:.1f} mm/s" + (f", f {low['f']:.2f}" if "f" in cases else "")
        lines.append(f"- jamming: none of {len(cases)} cases" + (f" (the rule: MFR < {rule:g})" if rule is not None else "")
                     + f"; the lowest MFR of a usable case {low['mfr']:.3f}, at {where}")
    if "flagged" in cases:
        marked = cases[flagged(cases)]
        where = (f": h/d {_span(marked['h_over_d'], '.2f')}, d {_span(marked['d_um'], '.0f')} um, "
                 f"v {_span(marked['v_mm_s'], '.1f')} mm/s{_flag_causes(marked)}" if len(marked) else "")
        lines.append(f"- flagged (kept out of training): {len(marked)} of {len(cases)} cases{where}")
    return lines


def _read_yaml(path: Path) -> dict:
    import yaml

    return (yaml.safe_load(path.read_text()) or {}) if path.exists() else {}


def _span(values: pd.Series, fmt: str) -> str:
    """'a-b' of a column's range, 'a' where it is one value."""
    low, high = format(values.min(), fmt), format(values.max(), fmt)
    return low if low == high else f"{low}-{high}"


def _flag_causes(marked: pd.DataFrame) -> str:
    """'; why: <cause> (count), ...' over the flagged cases' reasons: each reason's cause is what
    follows its last ': ' (e.g. 'the pile ran down'), or the reason with its numbers as '#'."""
    if "flag_reason" not in marked:
        return ""
    causes, texts = [], {}
    for reason in marked["flag_reason"].fillna(""):
        for part in filter(None, (p.strip() for p in str(reason).split(";"))):
            cause = part.rsplit(": ", 1)[1] if ": " in part else re.sub(r"\d+(\.\d+)?(e[-+]?\d+)?", "#", part)
            causes.append(cause)
            texts.setdefault(cause, part)
    counts = pd.Series(causes, dtype=object).value_counts()
    # a cause met once reads better with its own numbers ('peak overlap 0.0516 R > 0.05 R' over '# R > # R')
    named = {c: (c if n > 1 or ": " in texts[c] else texts[c]) for c, n in counts.items()}
    return "; why: " + ", ".join(f"{named[c]} ({n})" for c, n in counts.items()) if len(counts) else ""


def summary_markdown(study: Path | str, effects: dict[str, pd.DataFrame]) -> str:
    """summary.md of the study folder's files, its trends section from ``effects`` (``trends``).

    Writes no file. A part whose files do not exist yet says "not yet run".

    Parameters
    ----------
    study : pathlib.Path or str
        The study folder (docs/study); see the module docstring for what it reads.
    effects : dict of str to pandas.DataFrame
        The trends (``trends``); {}: the section says "not yet run".

    Returns
    -------
    str
        The Markdown text: a title, the floor (from config.yaml, if there) and one section per
        question.
    """
    study = Path(study)
    sections = [_cases(study), _convergence(study), _surrogate(study), _heldout(study), _ranking(study),
                _trends(effects), _regimes(study)]
    config = study / "config.yaml"
    floor = f"Floor: {floor_label(_read_yaml(config))}.\n\n" if config.exists() else ""
    return "# The study: what the data say\n\n" + floor + "\n\n".join("\n".join(s) for s in sections) + "\n"
