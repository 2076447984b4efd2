"""The numbers of the fidelity study: each preset's error of MFR and PD against the reference
preset, its seed-to-seed spread and its cost; and the same for each value of each knob against
the base preset's own value.

Errors are differences of seed means. Their noise is the standard error of that difference,
sqrt(s_a^2/n_a + s_b^2/n_b) with s the seed-to-seed standard deviation (ddof = 1). At one point
(and for a knob value) an error within twice its standard error (about a 95 % interval) is not
resolved by the seeds run. A preset's error is the mean |relative error| over the points; it is
"within noise" when a chi-square test of the points' errors against their standard errors does
not reject "no error" at 5 %, and it is reported with its noise floor (the mean |error| a preset
without any systematic error would show), never as an error of zero.

Cost is the CPU time of the YADE process (one core), far less disturbed by whatever else the
machine runs than wall time, which is reported beside it.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.stats import chi2 as chi2_dist

from ..design import TARGETS
from ..table import flagged, usable

RESOLVED_SIGMAS = 2.0  # an error beyond this many standard errors is resolved


def seed_statistics(table: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    """Per group: mean, seed SD and count of MFR and PD over usable cases; cost of all cases run."""
    table = table.copy()
    table["usable"] = usable(table)
    table["particle_steps"] = table["n_particles"] * table["steps"]
    rows = []
    for key, group in table.groupby(by, sort=False, dropna=False):
        ok = group[group["usable"]]
        row = dict(zip(by, key if isinstance(key, tuple) else (key,)))
        row.update({"cases": len(group), "usable_cases": len(ok)})
        for t in TARGETS:
            row[f"{t}_mean"] = ok[t].mean() if len(ok) else math.nan
            row[f"{t}_sd"] = ok[t].std(ddof=1) if len(ok) > 1 else math.nan
        row["cpu_s_mean"] = group["cpu_time"].mean()
        row["wall_s_mean"] = group["wall_time"].mean()
        row["n_particles"] = group["n_particles"].median()
        row["particle_steps_per_s"] = (group["particle_steps"] / group["cpu_time"]).median()
        rows.append(row)
    return pd.DataFrame(rows)


def compare(stats: pd.DataFrame, against: pd.DataFrame, on: list[str]) -> pd.DataFrame:
    """Add the error of each row of `stats` against the matching row of `against` (joined on `on`):
    difference, relative difference, its standard error and whether the seeds resolve it."""
    ref = against.set_index(on)
    out = stats.copy()
    keys = pd.MultiIndex.from_frame(out[on]) if len(on) > 1 else pd.Index(out[on[0]])
    n_ref = ref["usable_cases"].reindex(keys).to_numpy(dtype=float)
    for t in TARGETS:
        m_ref = ref[f"{t}_mean"].reindex(keys).to_numpy(dtype=float)
        s_ref = ref[f"{t}_sd"].reindex(keys).to_numpy(dtype=float)
        diff = out[f"{t}_mean"].to_numpy(dtype=float) - m_ref
        se = np.sqrt(out[f"{t}_sd"].to_numpy(dtype=float) ** 2 / out["usable_cases"].to_numpy(dtype=float)
                     + s_ref ** 2 / n_ref)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[f"{t}_ref"] = m_ref
            out[f"{t}_ref_sd"] = s_ref
            out[f"{t}_error"] = diff
            out[f"{t}_rel_error"] = diff / m_ref
            out[f"{t}_se"] = se
            out[f"{t}_rel_resolution"] = RESOLVED_SIGMAS * se / np.abs(m_ref)
        out[f"{t}_resolved"] = np.abs(diff) > RESOLVED_SIGMAS * se
    return out


def _aggregate(group: pd.DataFrame, t: str) -> dict:
    """One preset's error of target t over its points: the mean |relative error|, its noise floor
    (the mean |error| a preset without any systematic error would show: sqrt(2/pi) x the relative
    standard error, per point), the chi-square test of "no error at any point" and the seeds per
    preset and point that would resolve a 5 % error (2 standard errors <= 5 %)."""
    rel = group[f"{t}_rel_error"].to_numpy(dtype=float)
    rel_se = (group[f"{t}_se"] / group[f"{t}_ref"].abs()).to_numpy(dtype=float)
    z = group[f"{t}_error"].to_numpy(dtype=float) / group[f"{t}_se"].to_numpy(dtype=float)
    finite = np.isfinite(z)
    chi2 = float(np.sum(z[finite] ** 2))
    # seeds (at the preset and at the reference alike) for 2 standard errors of 5 % of the reference
    spread2 = (group[f"{t}_sd"] ** 2 + group[f"{t}_ref_sd"] ** 2).to_numpy(dtype=float)
    seeds_for_5 = (RESOLVED_SIGMAS / 0.05) ** 2 * spread2 / group[f"{t}_ref"].to_numpy(dtype=float) ** 2
    return {f"{t}_mean_abs_rel_error": float(np.nanmean(np.abs(rel))) if len(rel) else math.nan,
            f"{t}_mean_rel_resolution": float(np.nanmean(RESOLVED_SIGMAS * rel_se)) if len(rel) else math.nan,
            f"{t}_noise_floor": float(np.nanmean(math.sqrt(2 / math.pi) * rel_se)) if len(rel) else math.nan,
            f"{t}_points_resolved": int(group[f"{t}_resolved"].sum()),
            f"{t}_chi2": chi2, f"{t}_chi2_p": float(chi2_dist.sf(chi2, int(finite.sum()))) if finite.any() else math.nan,
            f"{t}_seeds_for_5pct": float(np.nanmedian(seeds_for_5)) if len(rel) else math.nan,
            f"{t}_seed_cv": float(np.nanmean(group[f"{t}_sd"] / group[f"{t}_mean"])) if len(rel) else math.nan}


def preset_verdict(row: dict, t: str) -> str:
    """A preset's error of target t as it reads in the tables: resolved (the chi-square test over
    the points rejects "no error" at 5 %), or within the noise, with the noise floor."""
    err, floor, p = row[f"{t}_mean_abs_rel_error"], row[f"{t}_noise_floor"], row[f"{t}_chi2_p"]
    if not (math.isfinite(err) and math.isfinite(p)):
        return "n/a"
    if p < 0.05:
        return f"{100 * err:.1f} % (resolved, p = {p:.2g})"
    return f"within noise ({100 * err:.1f} %; noise floor {100 * floor:.1f} %, p = {p:.2g})"


def verdict(rel_error: float, rel_resolution: float) -> str:
    """How an error reads in the tables: a resolved error, or an error within the noise."""
    if not (math.isfinite(rel_error) and math.isfinite(rel_resolution)):
        return "n/a"
    if abs(rel_error) > rel_resolution:
        return f"{100 * rel_error:+.1f} %"
    return f"within noise (|err| {100 * abs(rel_error):.1f} % < {100 * rel_resolution:.1f} %)"


def preset_errors(table: pd.DataFrame, reference: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(per point and preset, per preset) errors against `reference`, spreads and costs.

    Errors are differences of seed means with their standard errors (see the module docstring);
    costs are the YADE process's CPU time (one core), wall time beside it.

    Parameters
    ----------
    table : pandas.DataFrame
        The fidelity study's results table: one row per case, with ``preset``, ``name`` (the
        point), ``status``/``flagged``, ``mfr``, ``pd``, ``cpu_time`` and ``wall_time`` [s],
        ``n_particles``, ``steps`` and ``peak_overlap_ratio`` (``peak_overlap_free``, ``wedged``
        and ``n_passed`` are used when present).
    reference : str
        The preset the others are compared with.

    Returns
    -------
    per_point : pandas.DataFrame
        One row per (preset, point): seed means, seed SDs (ddof = 1) and counts of MFR and PD,
        costs, and the error against the reference's same point (``<t>_error``,
        ``<t>_rel_error``, ``<t>_se``, ``<t>_rel_resolution``, ``<t>_resolved``).
    presets : pandas.DataFrame
        One row per preset: the mean |relative error| over the points, its noise floor, the
        chi-square test (``<t>_chi2``, ``<t>_chi2_p``), ``<t>_verdict``, the seeds that would
        resolve 5 %, CPU and wall seconds (median, max, total), ``cost_ratio_to_reference``,
        particle-steps per CPU second and flagged cases.
    """
    per_point = compare(stats := seed_statistics(table, ["preset", "name"]), stats[stats["preset"] == reference], ["name"])
    rows = []
    ref_cpu = table.loc[table["preset"] == reference, "cpu_time"].sum()
    for preset, group in per_point.groupby("preset", sort=False):
        cases = table[table["preset"] == preset]
        row = {"preset": preset, "points": len(group), "cases": int(group["cases"].sum()),
               "usable_cases": int(group["usable_cases"].sum())}
        for t in TARGETS:
            row.update(_aggregate(group, t))
            row[f"{t}_verdict"] = "reference" if preset == reference else preset_verdict(row, t)
        row.update({"cpu_s_median": cases["cpu_time"].median(), "cpu_s_max": cases["cpu_time"].max(),
                    "wall_s_median": cases["wall_time"].median(), "wall_s_max": cases["wall_time"].max(),
                    "cpu_s_total": cases["cpu_time"].sum(),
                    "cost_ratio_to_reference": ref_cpu / cases["cpu_time"].sum(),
                    "particle_steps_per_s": (cases["n_particles"] * cases["steps"] / cases["cpu_time"]).median(),
                    "n_particles_median": cases["n_particles"].median(),
                    "flagged_cases": int(flagged(cases).sum()),
                    # the free peak (impacts, weight: the stability bound's) where the scene split it
                    "peak_overlap_max": cases.get("peak_overlap_free", cases["peak_overlap_ratio"]).max()})
        if "wedged" in cases:  # the scene tells a sphere pinned under the blade from the rest
            row["wedged_cases"] = int(cases["wedged"].astype(str).eq("True").sum())
        if "n_passed" in cases and cases["n_passed"].notna().any():  # windows sized by a precision target
            row["n_passed_median"] = cases["n_passed"].median()
        rows.append(row)
    return per_point, pd.DataFrame(rows)


def knob_errors(table: pd.DataFrame) -> pd.DataFrame:
    """Per knob and value: MFR and PD, their seed spread, the error against the base value and the
    cost relative to it.

    Parameters
    ----------
    table : pandas.DataFrame
        The one-knob-at-a-time results table: one row per case, with ``knob``, ``value``,
        ``is_base`` (the base preset's own value of the knob), ``preset``, ``status``/``flagged``,
        ``mfr``, ``pd``, ``cpu_time`` and ``wall_time`` [s], ``n_particles`` and ``steps``.

    Returns
    -------
    pandas.DataFrame
        One row per (knob, value), sorted by knob then value: seed statistics, the error against
        the knob's base value (as in ``preset_errors``), ``cost_ratio_to_base`` (mean CPU over
        the base's) and ``<t>_verdict``.
    """
    stats = seed_statistics(table, ["knob", "value", "is_base", "preset"])
    out = compare(stats, stats[stats["is_base"]], ["knob"])
    base_cpu = out[out["is_base"]].set_index("knob")["cpu_s_mean"]
    out["cost_ratio_to_base"] = out["cpu_s_mean"].to_numpy() / base_cpu.reindex(out["knob"]).to_numpy()
    for t in TARGETS:
        out[f"{t}_verdict"] = [("base" if b else verdict(e, r))
                               for b, e, r in zip(out["is_base"], out[f"{t}_rel_error"], out[f"{t}_rel_resolution"])]
    return out.sort_values(["knob", "value"], kind="stable").reset_index(drop=True)


def goal(presets: pd.DataFrame, candidate: str, max_rel_error: float = 0.05, min_cost_ratio: float = 20.0,
         max_median_cpu_s: float = 20.0) -> dict:
    """The goal for one preset: "met", "not met" when a check is resolved as missed, else "not
    resolved".

    The goal: within `max_rel_error` of the reference on MFR and PD (mean over the points),
    `min_cost_ratio` times cheaper, median CPU per case <= `max_median_cpu_s`. Accuracy is "met"
    only when the measured error plus its resolution is below the bound, "not met" when the error
    minus its resolution is above it, and otherwise "not resolved".

    Parameters
    ----------
    presets : pandas.DataFrame
        The per-preset table of ``preset_errors``.
    candidate : str
        The preset whose goal is checked.
    max_rel_error : float, optional
        Bound on the mean |relative error| of MFR and of PD (0.05 = 5 %).
    min_cost_ratio : float, optional
        How many times cheaper (total CPU) than the reference the preset must be.
    max_median_cpu_s : float, optional
        Bound on the median CPU time per case [s].

    Returns
    -------
    dict
        ``preset``, the three bounds, ``checks`` (per check: the measured value, its ``state``
        and ``met``; the accuracy checks add ``resolution``, ``noise_floor`` and
        ``seeds_for_5pct``), the overall ``state`` and ``met``.

    Raises
    ------
    KeyError
        If `candidate` is not a preset of `presets`.
    """
    row = presets.set_index("preset").loc[candidate]
    checks = {}
    for t in TARGETS:
        err, res = float(row[f"{t}_mean_abs_rel_error"]), float(row[f"{t}_mean_rel_resolution"])
        # demonstrated when even the error plus its resolution is below the bound, missed when the
        # error minus its resolution is above it, otherwise not resolved by the seeds run
        if err + res <= max_rel_error:
            state = "met"
        elif err - res > max_rel_error:
            state = "not met"
        else:
            state = "not resolved"
        checks[f"{t}_error"] = {"measured": err, "resolution": res, "noise_floor": float(row[f"{t}_noise_floor"]),
                                "seeds_for_5pct": float(row[f"{t}_seeds_for_5pct"]), "state": state,
                                "met": state == "met"}
    checks["cost_ratio"] = {"value": float(row["cost_ratio_to_reference"]),
                            "met": bool(row["cost_ratio_to_reference"] >= min_cost_ratio)}
    checks["median_cpu_s"] = {"value": float(row["cpu_s_median"]), "met": bool(row["cpu_s_median"] <= max_median_cpu_s)}
    for key in ("cost_ratio", "median_cpu_s"):
        checks[key]["state"] = "met" if checks[key]["met"] else "not met"
    states = {c["state"] for c in checks.values()}
    state = "not met" if "not met" in states else "not resolved" if "not resolved" in states else "met"
    return {"preset": candidate, "max_rel_error": max_rel_error, "min_cost_ratio": min_cost_ratio,
            "max_median_cpu_s": max_median_cpu_s, "checks": checks, "state": state, "met": state == "met"}


def _pct(x: float) -> str:
    return f"{100 * x:.1f} %" if math.isfinite(x) else "n/a"


def markdown_summary(presets: pd.DataFrame, per_point: pd.DataFrame, knobs: pd.DataFrame | None,
                     reference: str, goals: list[dict]) -> str:
    """The study's tables as Markdown (for the README and for people).

    Parameters
    ----------
    presets : pandas.DataFrame
        The per-preset table of ``preset_errors``.
    per_point : pandas.DataFrame
        The per-point table of ``preset_errors``.
    knobs : pandas.DataFrame or None
        The table of ``knob_errors``; None or empty: no knob section.
    reference : str
        The reference preset.
    goals : list of dict
        Results of ``goal``, one section each.

    Returns
    -------
    str
        The Markdown text, ending with a line break.
    """
    lines = [f"### Presets against `{reference}`", "",
             "Error: mean over the points of |seed mean - reference seed mean| / reference seed mean. "
             "\"Within noise\" when a chi-square test of the points' errors against their standard errors "
             "does not reject \"no error\" at 5 %; the noise floor is the mean error a preset without any "
             "systematic error would show with these seeds. Per point and knob value: \"within noise\" when "
             "|error| is below 2 standard errors of the difference of the seed means. Seed spread: mean over "
             "the points of the seed-to-seed coefficient of variation. Cost: CPU time of one YADE process "
             "(one core); \"cost vs reference\": the reference's total CPU time over the preset's.", "",
             "| preset | spheres (median) | N passed (median) | CPU per case, median / max | wall per case, median "
             "| cost vs reference | particle-steps/s | MFR error | PD error | seed spread MFR / PD | usable cases "
             "| peak free overlap (max) | wedged cases |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in presets.iterrows():
        cost = "1 (reference)" if r["preset"] == reference else f"{r['cost_ratio_to_reference']:.1f}x cheaper"
        n_passed = f"{r['n_passed_median']:.0f}" if pd.notna(r.get("n_passed_median")) else "-"
        wedged = f"{r['wedged_cases']:.0f}" if pd.notna(r.get("wedged_cases")) else "-"
        lines.append(f"| {r['preset']} | {r['n_particles_median']:.0f} | {n_passed} "
                     f"| {r['cpu_s_median']:.1f} s / {r['cpu_s_max']:.0f} s "
                     f"| {r['wall_s_median']:.1f} s | {cost} "
                     f"| {r['particle_steps_per_s']:.2e} | {r['mfr_verdict']} | {r['pd_verdict']} "
                     f"| {_pct(r['mfr_seed_cv'])} / {_pct(r['pd_seed_cv'])} | {r['usable_cases']}/{r['cases']} "
                     f"| {_pct(r['peak_overlap_max'])} R | {wedged} |")
    lines += ["", "### Per point (seed mean +- seed SD)", "",
              "| point | preset | MFR | PD | MFR error | PD error | CPU per case |", "|---|---|---|---|---|---|---|"]
    for _, r in per_point.sort_values(["name", "preset"], kind="stable").iterrows():
        errs = ["reference" if r["preset"] == reference else verdict(r[f"{t}_rel_error"], r[f"{t}_rel_resolution"])
                for t in TARGETS]
        lines.append(f"| {r['name']} | {r['preset']} | {r['mfr_mean']:.3f} +- {r['mfr_sd']:.3f} "
                     f"| {r['pd_mean']:.3f} +- {r['pd_sd']:.3f} | {errs[0]} | {errs[1]} | {r['cpu_s_mean']:.0f} s |")
    if knobs is not None and len(knobs):
        lines += ["", "### One knob at a time (error against the base preset's own value)", "",
                  "| knob | value | MFR | PD | MFR error | PD error | cost vs base |", "|---|---|---|---|---|---|---|"]
        for _, r in knobs.iterrows():
            lines.append(f"| {r['knob']} | {r['value']:g} | {r['mfr_mean']:.3f} +- {r['mfr_sd']:.3f} "
                         f"| {r['pd_mean']:.3f} +- {r['pd_sd']:.3f} | {r['mfr_verdict']} | {r['pd_verdict']} "
                         f"| {r['cost_ratio_to_base']:.2f}x |")
    for g in goals:
        c = g["checks"]
        lines += ["", f"### Goal for `{g['preset']}`: {g['state']}", "",
                  *[f"- {t.upper()} error {_pct(c[f'{t}_error']['measured'])} against {_pct(g['max_rel_error'])}: "
                    f"{c[f'{t}_error']['state']} (resolution {_pct(c[f'{t}_error']['resolution'])}, noise floor "
                    f"{_pct(c[f'{t}_error']['noise_floor'])}; ~{c[f'{t}_error']['seeds_for_5pct']:.0f} seeds per point "
                    f"would resolve 5 %)" for t in TARGETS],
                  f"- cost {c['cost_ratio']['value']:.1f}x below the reference against {g['min_cost_ratio']:g}x: "
                  f"{c['cost_ratio']['state']}",
                  f"- median CPU per case {c['median_cpu_s']['value']:.1f} s against {g['max_median_cpu_s']:g} s: "
                  f"{c['median_cpu_s']['state']}"]
    return "\n".join(lines) + "\n"


def machine_description(table: pd.DataFrame) -> dict:
    """Where and when the numbers were measured, with the YADE versions of the cases.

    Parameters
    ----------
    table : pandas.DataFrame
        The cases' results table (its ``yade_version`` column is read if present).

    Returns
    -------
    dict
        ``spreadmap.host.description()`` (this machine, now) plus ``yade``: the sorted
        distinct YADE versions of the cases.
    """
    from ..host import description

    versions = sorted(set(table.get("yade_version", pd.Series(dtype=str)).dropna().astype(str)))
    return {**description(), "yade": versions}
