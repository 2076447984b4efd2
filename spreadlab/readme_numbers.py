"""The numbers README.md states, re-derived from the published tables under docs/ (issue 52).

Each claim is a phrase of README.md with ``{}`` where a number stands, the tables it comes from
(file, column, statistic) and a function that computes those numbers from them. A stated number
holds when the derived one rounds to it: the tolerance is half a unit of its last printed digit
(README's rounding), so "1.41" holds 1.405-1.415 and "23" holds 22.5-23.5. A phrase no longer in
README.md is reported as not found (the claim then needs its new wording here). A few numbers are
in no table, only in the prose of a published page (the main job's wall times): those are checked
against that page's text, and say so. ``tools/readme_numbers.py`` prints the check;
``tests/docs/test_readme_numbers.py`` runs it on the committed tables.
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import pandas as pd
from scipy import stats

from spreadmap import design
from spreadmap.run_report import set_summary

NUMBER = r"([-+]?\d+(?:\.\d+)?)"


@dataclass(frozen=True)
class Claim:
    """One README phrase with its numbers (``{}``), their source and their derivation."""

    label: str
    phrase: str
    source: str
    derive: Callable[[Path], Sequence]  # per number a float, or (float, error it carries beyond README's rounding)


@dataclass(frozen=True)
class Row:
    """One stated number against the number derived from the tables."""

    label: str
    stated: str | None
    derived: float
    tolerance: float
    status: str  # "ok", "MISMATCH" or "NOT FOUND"
    source: str


def tolerance(stated: str) -> float:
    """Half a unit of the last printed digit of a stated number ("1.41" -> 0.005, "23" -> 0.5).

    Parameters
    ----------
    stated : str
        The number as README prints it.

    Returns
    -------
    float
        The largest difference from the derived number that the rounding explains.
    """
    decimals = len(stated.split(".")[1]) if "." in stated else 0
    return 0.5 * 10.0 ** -decimals * (1 + 1e-9)


def phrase_regex(phrase: str) -> re.Pattern:
    """The regular expression of a claim's phrase: its text literally (any whitespace for a space),
    a number for each ``{}``."""
    parts = [re.escape(p).replace(r"\ ", r"\s+") for p in phrase.split("{}")]
    return re.compile(NUMBER.join(parts))


# ---------------------------------------------------------------- reading the published tables

@cache
def _csv(path: Path) -> pd.DataFrame:
    return pd.read_csv(path)


@cache
def _json(path: Path):
    return json.loads(path.read_text())


def _prose(path: Path, phrase: str) -> list[float]:
    """Numbers a published page states in its prose (for numbers no table holds)."""
    match = phrase_regex(phrase).search(path.read_text())
    return [float(x) for x in match.groups()] if match else [math.nan] * phrase.count("{}")


def _run(docs: Path, day: str) -> Path:
    return docs / "main_job" / f"run_{day}"


def _heldout(docs: Path, folder: str, target: str) -> dict:
    return next(s for s in _json(docs / "main_job" / folder / "score.json") if s["target"] == target)


def _chi2_upper(rmse: float, n: int) -> float:
    """95 % upper bound of an RMS error over n points (chi-square on n dof)."""
    return rmse * math.sqrt(n / stats.chi2.ppf(0.05, n))


def _cpu_share_of_corner_cases(docs: Path) -> list[float]:
    c = _csv(_run(docs, "2026-12-04") / "cases.csv")
    corner = (c["d_um"] <= 12.5) & (design.h_over_d(c) >= 5.5)
    return [100 * c.loc[corner, "cpu_time"].sum() / c["cpu_time"].sum()]


def _main_job_cpu(docs: Path) -> list[float]:
    cpu = _csv(_run(docs, "2026-12-04") / "cases.csv")["cpu_time"]
    return [cpu.median(), cpu.max(), cpu.max() / cpu.median()]


def _seed_cv_rms(per_point: Path, preset: str) -> list[float]:
    """RMS over the points of the seed-to-seed CV (per_point.csv's SD / mean), in %."""
    p = _csv(per_point)
    p = p[p["preset"] == preset]
    return [100 * math.sqrt(float(np.mean((p[f"{t}_sd"] / p[f"{t}_mean"]) ** 2))) for t in ("mfr", "pd")]


def _preset(presets: Path, preset: str) -> pd.Series:
    p = _csv(presets)
    return p[p["preset"] == preset].iloc[0]


def _factor(docs: Path, target: str) -> dict:
    return _json(docs / "fidelity" / "correction" / "correction.json")["targets"][target]


def _arm_point_cpu_ratio(cases: pd.DataFrame, arm: str, base: str) -> pd.Series:
    """Per point, the mean CPU of an arm's finished cases over the base arm's."""
    m = cases[cases["status"] == "ok"].groupby(["arm", "point"])["cpu_time"].mean()
    return m[arm] / m[base]


def _adhesion(docs: Path) -> list[float]:
    a = _csv(docs / "adhesion" / "scaling_cases.csv")
    ok = a[a["status"] == "ok"]
    cpu = ok.groupby("arm")["cpu_time"]
    geo = {arm: float(np.exp(np.log(_arm_point_cpu_ratio(a, arm, base)).mean()))
           for arm, base in (("adh_x1000", "dry_x1000"), ("adh_x100", "adh_x1000"), ("adh_x10", "adh_x1000"))}
    mfr = ok[~ok["flagged"].astype(bool)].groupby(["arm", "point"])["mfr"].mean()
    low = {arm: 100 * (mfr["adh_x10"] - mfr[arm]) / mfr["adh_x10"] for arm in ("adh_x1000", "adh_x100")}
    return [geo["adh_x1000"], cpu.median()["adh_x1000"], cpu.median()["dry_x1000"],
            cpu.max()["adh_x1000"], cpu.max()["dry_x1000"],
            low["adh_x1000"]["coarse"], low["adh_x1000"]["fine"], low["adh_x100"].min(), low["adh_x100"].max(),
            geo["adh_x100"], geo["adh_x10"]]


def _size_distribution(docs: Path) -> list[float]:
    c = _csv(docs / "size_distribution" / "cost_cases.csv")
    c = c[c["seed"].astype(int) <= 2]  # the run that held every arm, interleaved (seeds 3-8: the tails' arms alone)
    cpu = c[c["status"] == "ok"].groupby("arm")["cpu_time"]
    d5, d1 = _arm_point_cpu_ratio(c, "span1_d5", "one_size"), _arm_point_cpu_ratio(c, "span1_d1", "one_size")
    return [d5["coarse"], d5["fine"], cpu.median()["span1_d5"], cpu.median()["one_size"],
            cpu.max()["span1_d5"], cpu.max()["one_size"], d1.min(), d1.max()]


def _overlap_stride(docs: Path) -> list[float]:
    o = _csv(docs / "case_cost" / "overlap_stride.csv")
    pairs = o.pivot_table(index=["point", "seed"], columns="arm", values="cpu_time")
    logs = np.log(pairs["stride"] / pairs["every_step"])
    se = logs.std(ddof=1) / math.sqrt(len(logs))  # benchmarks/overlap_stride.py: normal 95 %
    return [math.exp(logs.mean()), math.exp(logs.mean() - 1.96 * se), math.exp(logs.mean() + 1.96 * se), len(logs)]


def _heap_size(docs: Path) -> list[float]:
    """A heap of 3 h^2: its CPU over 4.7 h^2's at the corner and at the wide point, the corner's MFR
    shift from 4.7 h^2, its SE, and the corner's h/d (the README's order)."""
    h = _csv(docs / "heap_size" / "cases.csv")
    rough = h[(h["floor"] == "rough") & (h["status"] == "ok")]  # flagged kept, as docs/heap_size reads them
    cpu = rough.groupby(["point", "pile_reserve"])["cpu_time"].median()
    corner = rough[rough["point"] == "corner"].groupby("pile_reserve")["mfr"]
    se = corner.std() / np.sqrt(corner.count())
    return [cpu["corner", 3.0] / cpu["corner", 4.7], cpu["wide", 3.0] / cpu["wide", 4.7],
            corner.mean()[3.0] - corner.mean()[4.7], math.hypot(se[3.0], se[4.7]),
            float(design.h_over_d(rough[rough["point"] == "corner"].iloc[0]))]


def _md_ratio(path: Path, what: str) -> list[tuple[float, float]]:
    """An A/B summary's "arm / shipped = R (... L-H)" line, as shipped / arm: 1/R (1/H-1/L), each
    with the error its inversion carries from the summary's two decimals (0.005 / x^2)."""
    m = re.search(what + r" = ([\d.]+) \(95 % interval from resampling seeds ([\d.]+)-([\d.]+)\)",
                  path.read_text())
    r, lo, hi = (float(x) for x in m.groups())
    return [(1 / x, 0.005 / x ** 2) for x in (r, hi, lo)]


def _issue31(docs: Path) -> list:
    cc = docs / "case_cost"
    seven = _md_ratio(cc / "final_summary.md", r"CPU\*\*: the points' mean CPU summed, arm / shipped")
    corner = _md_ratio(cc / "final_corner_summary.md", r"CPU\*\*: the points' mean CPU summed, arm / shipped")
    box = _json(cc / "cost_map.json")["mean_ratio"]
    return [*seven, *corner, box["ratio"], *box["ci95"]]


def _cost_map_default(docs: Path) -> list[float]:
    rows = _json(docs / "case_cost" / "cost_map.json")["rows"]
    r = next(r for r in rows if (r["arm"], r["preset"], r["scale"]) == ("shipped", "default", "this machine"))
    return [r["median"], r["max"], r["max_over_median"], *_main_job_cpu(docs)]


def _issue31_mfr(docs: Path) -> list[float]:
    m = re.search(r"issue31_start, MFR\*\*: chi-square over the (\d+) points = ([\d.]+) \(\d+ dof, p = ([\d.]+)",
                  (docs / "case_cost" / "final_summary.md").read_text())
    return [float(m[2]), float(m[1]), float(m[3])]


def _floors(docs: Path) -> list[float]:
    b = _csv(docs / "floors" / "compare" / "by_band.csv")
    b = b[b["target"] == "mfr"]
    thin, wide = b[b["h_over_d_below"] <= 2.0], b[b["h_over_d_from"] >= 5.0]
    return [wide["ratio_median"].iloc[0], thin["ratio_median"].min(), thin["ratio_median"].max(),
            thin["ratio_min"].min(), thin["ratio_max"].max()]


def _noise_adhesive(docs: Path) -> list[float]:
    law = _json(docs / "noise" / "adhesive" / "law.json")
    by_hd = [(hd, x) for t in ("mfr", "pd") for table in [law["targets"][t]["factor_over_dry"][law["chosen"]]]
             for hd, x in zip(table["h_over_d"], table["factor"])]
    out = [law["points"], law["dof"]]
    for lo, hi in ((1.1, 1.1), (2.0, 2.0), (4.0, 6.0)):
        f = [x for hd, x in by_hd if lo <= hd <= hi]
        out += [min(f), max(f)]
    return out


def _replay_row(path: Path) -> pd.Series:
    h = _csv(path)
    return h[(h["rule"].str.startswith("x1.7")) & (h["tolerance"] == 0.02) & (h["design"] == "active_per_cpu")].iloc[0]


def _map_tolerance(docs: Path, day: str) -> float:
    """The MFR tolerance a run's stop judged its map error against (its summary: "mfr: E of T")."""
    return float(re.search(r"mfr: [\d.]+ of ([\d.]+)", _stop(docs, day)["summary"])[1])


def _dry_main_job(docs: Path) -> list[float]:
    tol = _map_tolerance(docs, "2026-12-04")
    metrics = _csv(_run(docs, "2026-12-04") / "surrogate_metrics.csv")
    noise = metrics[(metrics["target"] == "mfr") & (metrics["model"] == "gp")]["noise_sd"].iloc[0]
    mean_mfr = _stop(docs, "2026-12-04")["map_statistics"]["mfr"]["mean"]["value"]
    return [tol, 100 * tol / mean_mfr, tol / noise]


def _heldout_dry(docs: Path) -> list[float]:
    mfr, pd_ = _heldout(docs, "run_2026-12-04/heldout", "mfr"), _heldout(docs, "run_2026-12-04/heldout", "pd")
    runs = _csv(_run(docs, "2026-12-04") / "heldout" / "score.csv")["n_runs"].unique()
    n = mfr["points"]
    return [n, runs[0] if len(runs) == 1 else math.nan, mfr["rmse"], pd_["rmse"], _chi2_upper(mfr["rmse"], n),
            _chi2_upper(pd_["rmse"], n), mfr["inside"], pd_["inside"], n]


def _heldout_adhesive(docs: Path) -> list[float]:
    s = _csv(_run(docs, "2026-12-06") / "heldout_reference" / "score.csv")
    e = s[s["target"] == "mfr"]["error"]
    rmse = math.sqrt(float((e ** 2).mean()))
    return [len(e), e.mean(), e.std(ddof=1) / math.sqrt(len(e)), rmse, rmse / _map_tolerance(docs, "2026-12-06")]


def _preset_row(docs: Path, preset: str) -> list[float]:
    """CPU median / max, cost against `reference`, seed spread (RMS) and error of a 2026-12-02 preset."""
    p = _preset(docs / "fidelity" / "presets.csv", preset)
    return [p["cpu_s_median"], p["cpu_s_max"], p["cost_ratio_to_reference"],
            *_seed_cv_rms(docs / "fidelity" / "per_point.csv", preset)]


def _corrected_row(docs: Path, preset: str) -> list[float]:
    c = docs / "fidelity" / "correction"
    p = _preset(c / "presets.csv", preset)
    return [p["cpu_s_median"], p["cpu_s_max"], *_seed_cv_rms(c / "per_point.csv", preset)]


def _correction_study(docs: Path) -> list[float]:
    pp = _csv(docs / "fidelity" / "correction" / "pairs.csv")
    cases = _csv(docs / "fidelity" / "correction" / "cases.csv")
    return [pp["h_over_d"].min(), pp["h_over_d"].max(), len(cases)]


def _study(docs: Path) -> list[float]:
    files = sorted((docs / "study").glob("cases_*.csv")) + sorted((docs / "study").glob("*_gap_seeds.csv"))
    cases = pd.concat([_csv(f) for f in files]).drop_duplicates("case_id")
    return [len(cases), cases["cpu_time"].sum() / 3600]


def _stop(docs: Path, day: str) -> dict:
    return _json(_run(docs, day) / "stopped.json")


MAIN_JOB = "docs/main_job/run_2026-12-04/"
ADHESIVE = "docs/main_job/run_2026-12-06/"
ADHESIVE_B = "docs/main_job/run_2026-12-06b/"
FRONT_RUN = "2026-12-07e"  # the main job the README's front paragraph reports
ADHESIVE_C = f"docs/main_job/run_{FRONT_RUN}/"
SETUP_C = 47  # s, the set-up before the run's first job (the command at 18:16:43, the run's log from 18:17:30.1)


def _analyses_written(docs: Path) -> float:
    """Minutes from the command to the last of the maps, decisions and explorer page (FRONT_RUN)."""
    t = _csv(_run(docs, FRONT_RUN) / "timeline.csv")
    return float(t[t["rule"].isin(["maps", "decide", "explorer"])]["end_min"].max()) + SETUP_C / 60


def _window_5d_cost(docs: Path) -> list[float]:
    """The 5 d window's run (run_2026-12-07d) against the 3 d window's (run_2026-12-07c_again), paired by
    design point (the case id less its content key): the median over the pairs of the CPU ratio, and
    the pairs."""
    five = _csv(_run(docs, "2026-12-07d") / "cases.csv")
    three = _csv(_run(docs, "2026-12-07c_again") / "cases.csv")
    for t in (five, three):
        t["point"] = t["case_id"].str.rsplit("-", n=1).str[0]
    m = five.merge(three, on="point", suffixes=("", "_3d"))
    return [float((m["cpu_time"] / m["cpu_time_3d"]).median()), len(m)]


def _trend(docs: Path, day: str) -> list[float]:
    """Mean flow-trend z of a main job's cases and its SE."""
    z = _csv(_run(docs, day) / "cases.csv")["flow_trend_z_batch"].dropna()
    return [float(z.mean()), float(z.std(ddof=1) / math.sqrt(len(z)))]


def _window_5d_trend(docs: Path) -> list[float]:
    """Mean flow-trend z (and its SE) of the 5 d window's run, and the 3 d window's mean."""
    return [*_trend(docs, "2026-12-07d"), _trend(docs, "2026-12-07c")[0]]


def _transient_fed(docs: Path) -> list[float]:
    """The 5 d window with the transient fed (`window5_fed_transient`) against `shipped`, the
    pre-registered seeds 1-2 paired by point and seed (``spreadmap.experiments.paired``): the
    geometric mean CPU ratio and its 95 % t interval, the pairs; the largest point's MFR shift (mean
    over its seeds) over `shipped`'s mean in %, its z against the cases' recorded SDs (eight points,
    as the phrase says)."""
    from spreadlab.experiments.paired import by_point, cpu_ratio, pairs

    t = _csv(docs / "steady_window" / "transient_fed" / "cases.csv")
    p = pairs(t[t["seed"].isin([1, 2])], "window5_fed_transient", "shipped")
    points = by_point(p, "mfr")
    if len(points) != 8:  # the phrase says "of eight"
        raise ValueError(f"{len(points)} points paired, the README says eight")
    worst = points.loc[points["z"].idxmax()]
    return [*cpu_ratio(p), len(p), 100 * worst["diff"] / worst["base"], worst["z"]]


def _exact_ci(k: int, n: int) -> tuple[float, float]:
    """The 95 % exact (Clopper-Pearson) interval of k successes in n, as the replay states it
    (spreadmap.experiments.replay.honesty: scipy's binomtest)."""
    from scipy.stats import binomtest

    ci = binomtest(k, n).proportion_ci(0.95, method="exact")
    return ci.low, ci.high


def _batch8_adhesive(docs: Path) -> list[float]:
    import yaml

    conv = yaml.safe_load((docs.parent / "config.yaml").read_text())["converge"]
    st = _csv(docs / "replay" / "adhesive" / "batch8" / "stops.csv")
    st = st[(st["design"] == f"active_per_cpu_b{conv['batch']}") & (st["rule"] == "bare estimate")
            & (st["margin"].astype(float) == float(conv["map_error"]["margin"]))]
    stops = st[st["stopped"].astype(bool)]
    k, n = int(stops["true_within"].astype(bool).sum()), len(stops)
    return [conv["map_error"]["margin"], conv["batch"], conv["min_stop_cases"], k, n, len(st), *_exact_ci(k, n)]


def _lever_pairs(docs: Path, table: str, arm: str):
    """Session 32's A/Bs against `shipped` (docs/steady_window/window5_pile3): the pairs of one arm."""
    from spreadlab.experiments.paired import pairs

    return pairs(_csv(docs / "steady_window" / "window5_pile3" / table), arm, "shipped")


def _reads2_lever(docs: Path) -> list[float]:
    """The overlap read twice a contact: CPU ratio, its 95 % CI, the pairs."""
    from spreadlab.experiments.paired import cpu_ratio

    p = _lever_pairs(docs, "reads2_cases.csv", "reads2")
    return [*cpu_ratio(p), len(p)]


def _later_window_lever(docs: Path) -> list[float]:
    """The later window on the pile of 3 d: CPU ratio, its 95 % CI, the pairs, MFR shift in % and its 90 % CI."""
    from spreadlab.experiments.paired import cpu_ratio, relative_shift

    p = _lever_pairs(docs, "cases.csv", "window5_pile3")
    return [*cpu_ratio(p), len(p), *(100 * x for x in relative_shift(p, "mfr"))]


def _replay_steady_window(docs: Path) -> list[float]:
    """The shipped loop's replay on the steady window's truth: stops within the tolerance, replays, 95 % CI."""
    st = _csv(docs / "replay" / "adhesive" / "steady_window" / "stops_margin1.csv")
    k, n = int(st["true_within"].astype(bool).sum()), len(st)
    return [k, n, *_exact_ci(k, n)]


CLAIMS: list[Claim] = [
    Claim("front figure: the dry main job's cases and CPU hours",
          "({} cases to its map criteria, {} CPU hours",
          MAIN_JOB + "stopped.json: n, cpu_hours",
          lambda d: [_stop(d, "2026-12-04")["n"], _stop(d, "2026-12-04")["cpu_hours"]]),
    Claim("front figure: the maps' MFR factor", "`reference` (MFR x{}; the layer fill",
          "docs/fidelity/correction/correction.json: targets.mfr.factor",
          lambda d: [_factor(d, "mfr")["factor"]]),
    Claim("adhesive main job (batches of 8): cases, CPU h", "met its map criteria at {} cases ({} CPU h)",
          ADHESIVE_C + "stopped.json: n, cpu_hours",
          lambda d: [_stop(d, FRONT_RUN)["n"], _stop(d, FRONT_RUN)["cpu_hours"]]),
    Claim("adhesive main job (batches of 8): minutes to the maps, decisions and explorer",
          "explorer page **{} min** after the",
          ADHESIVE_C + "timeline.csv: the last end_min of maps, decide, explorer + the set-up (47 s, the run's log)",
          lambda d: [_analyses_written(d)]),
    Claim("adhesive main job (batches of 8): the whole run's minutes", "the surrogate's validation last, {} min",
          ADHESIVE_C + "timeline.json: wall_s / 60, + the set-up before the first job (47 s, the run's log)",
          lambda d: [(_json(_run(d, FRONT_RUN) / "timeline.json")["wall_s"] + SETUP_C) / 60]),
    Claim("adhesive main job (batches of 8): map error of MFR and PD at the stop, tolerance",
          "map error MFR {} and PD {} against the {} tolerance",
          ADHESIVE_C + "stopped.json: criteria.at_this_batch.map_error.targets.*.estimate, tolerance",
          lambda d: (lambda t: [t["mfr"]["estimate"], t["pd"]["estimate"], t["mfr"]["tolerance"]])(
              _stop(d, FRONT_RUN)["criteria"]["at_this_batch"]["map_error"]["targets"])),
    Claim("the shipped loop's replay on the steady window's truth: honest stops, replays, 95 % CI",
          "on the new scene's truth {} of {}, {}-{})",
          "docs/replay/adhesive/steady_window/stops_margin1.csv: true_within, Clopper-Pearson", _replay_steady_window),
    Claim("the front run: mean flow-trend z (SE)", "its cases' mean flow-trend z +{} (SE {})",
          ADHESIVE_C + "cases.csv: flow_trend_z_batch, mean and SE", lambda d: _trend(d, FRONT_RUN)),
    Claim("session 32: the overlap read twice a contact against four times (CPU, 95 % CI, pairs)",
          "(two reads a contact) **{}x** that (95 % CI {}-{}, {} pairs, to the bit",
          "docs/steady_window/window5_pile3/reads2_cases.csv: spreadmap.experiments.paired, reads2 against shipped",
          _reads2_lever),
    Claim("session 32: the later window on a 3 d pile (CPU, 95 % CI, pairs, MFR % and its 90 % CI)",
          "3 d at **{}x** (95 % CI {}-{}, {} pairs; MFR +{} %, 90 % CI {} to +{};",
          "docs/steady_window/window5_pile3/cases.csv: spreadmap.experiments.paired, window5_pile3 against shipped",
          _later_window_lever),
    Claim("the 5 d window: CPU per case paired with the 3 d window's run, pairs",
          "at **{}x the CPU per case** ({} points paired)",
          "docs/main_job/run_2026-12-07d/cases.csv, run_2026-12-07c_again/cases.csv: median cpu_time ratio "
          "over the design points both ran",
          _window_5d_cost),
    Claim("the 5 d window: mean flow-trend z (SE) of its run, and the 3 d window's",
          "mean flow-trend z +{}, SE {}, against +{})",
          "docs/main_job/run_2026-12-07d/cases.csv, run_2026-12-07c/cases.csv: flow_trend_z_batch, mean and SE",
          _window_5d_trend),
    Claim("the 5 d window with the transient fed: CPU ratio (95 % CI), pairs; MFR at the worst point (of eight), z",
          "at **{}x** (95 % CI {}-{}, {} pairs), but MFR {} % high at one point of eight (z {};",
          "docs/steady_window/transient_fed/cases.csv (seeds 1-2): window5_fed_transient / shipped paired by point "
          "and seed, geometric mean and t interval; per point mean MFR shift over shipped's, z from mfr_sd",
          _transient_fed),
    Claim("the adhesive replay of the shipped loop: margin, batch, fewest cases, stops honest, stops, replays, 95 % CI",
          "(margin {}, batches of {}, stops from {} cases: {} of {} stops within the tolerance on {} replays, 95 % CI {}-{}",
          "config.yaml converge; docs/replay/adhesive/batch8/stops.csv (design of the config's batch, bare "
          "estimate at its margin): true_within, stopped rows, rows, Clopper-Pearson",
          _batch8_adhesive),
    Claim("adhesive map against `reference`: points, MFR bias (SE), RMS, RMS / tolerance",
          "blind at {} new points run at `reference` (density x100), read MFR {} (SE {}) low, {} RMS, {}x",
          ADHESIVE + "heldout_reference/score.csv (target mfr): rows, mean and SE of error, RMS of error, / the tolerance",
          _heldout_adhesive),
    Claim("adhesive noise law: points, dof, its SD over the dry law's at h/d 1.1, 2, 4-6 (MFR and PD)",
          "({} points, {} dof: the noise {}-{}x the dry law's at h/d 1.1, {}-{}x at 2, {}-{}x at 4-6",
          "docs/noise/adhesive/law.json: points, dof, targets.*.factor_over_dry[chosen] (min-max over MFR, PD)",
          _noise_adhesive),
    Claim("dry main job: tolerance, as % of the map's mean MFR, over one run's noise (the noise law's)",
          "**MFR and PD within {} RMS** (about {} % of the mean MFR, {}x",
          MAIN_JOB + "stopped.json map_statistics.mfr.mean; surrogate_metrics.csv noise_sd (gp, mfr: RMS of "
          "the cases' SDs, which the noise law sets)",
          _dry_main_job),
    Claim("the stop rule on held-out replays: replays, stops within tolerance, stops, 95 % CI",
          "(on {} replays its margin was not calibrated on, {} of {} stops within tolerance, 95 % CI {}-{})",
          "docs/replay/heldout50/honesty.csv (x1.7, 0.02, active_per_cpu): replays, within, stops, honest_low/high",
          lambda d: (lambda r: [r["replays"], r["within"], r["stops"], r["honest_low"], r["honest_high"]])(
              _replay_row(d / "replay" / "heldout50" / "honesty.csv"))),
    Claim("the loop's start, batch and CPU budget",
          "adaptive loop: {} LDS cases, then batches of {} until the map's error holds or {} modelled CPU",
          MAIN_JOB + "stopped.json: settings start, batch, cpu_budget_h",
          lambda d: [_stop(d, "2026-12-04")["settings"][k] for k in ("start", "batch", "cpu_budget_h")]),
    Claim("the maps' correction factors and the factor's SD at a new point",
          "(x{} MFR, x{} PD; its uncertainty, {} % at a point no pair ran",
          "docs/fidelity/correction/correction.json: targets.mfr/pd.factor, targets.mfr.sd",
          lambda d: [_factor(d, "mfr")["factor"], _factor(d, "pd")["factor"], 100 * _factor(d, "mfr")["sd"]]),
    Claim("rough / flat MFR: median at h/d >= 5; the bands' medians and the points' range at h/d < 2",
          "median by band: {}x at h/d >= 5 up to {}-{}x at h/d < 2, {}-{}x by point there;",
          "docs/floors/compare/by_band.csv (mfr): ratio_median, ratio_min, ratio_max by band",
          _floors),
    Claim("dry main job: set-up, stop and end minutes (no table: the page's prose)",
          "set-up {} s, then **the loop met its criteria at {} cases after {} min** and the maps",
          "docs/main_job/README.md prose ('Set-up 55 s', 'criteria met at 96 cases, 52 min'); stopped.json n",
          lambda d: [_prose(d / "main_job" / "README.md", "**Set-up {} s**")[0], _stop(d, "2026-12-04")["n"],
                     _prose(d / "main_job" / "README.md", "criteria met at {} cases, {} min after set-up")[1]]),
    Claim("dry main job: end of the analyses (no table: the page's prose)",
          "explorer page were written at **{} min**",
          "docs/main_job/README.md prose ('end at **57 min**')",
          lambda d: _prose(d / "main_job" / "README.md", "explorer) end at **{} min**")),
    Claim("dry main job: CPU h measured, modelled, cases neither flagged nor failed",
          "{} CPU hours measured ({} modelled), none of the {} cases flagged or failed",
          MAIN_JOB + "stopped.json cpu_hours, cpu_hours_modelled; cases.csv usable (spreadmap.run_report)",
          lambda d: [_stop(d, "2026-12-04")["cpu_hours"], _stop(d, "2026-12-04")["cpu_hours_modelled"],
                     set_summary(_csv(_run(d, "2026-12-04") / "cases.csv"))["usable"]]),
    Claim("dry map's blind check: points, seeds, RMS MFR / PD, upper bounds, inside",
          "checked blind at {} new points ({} seeds each, predictions committed before the runs): RMS error {} MFR, "
          "{} PD with the runs' noise in it (95 % upper bounds {}, {}), {} and {} of {} inside",
          MAIN_JOB + "heldout/score.json: points, rmse, inside; score.csv n_runs; bound rmse sqrt(n / chi2_0.05(n))",
          _heldout_dry),
    Claim("dry main job: the CPU share of its corner cases",
          "at d 10-12 um and h/d 6-7 take {} % of the CPU",
          MAIN_JOB + "cases.csv: the cpu_time share of the (three) cases at d <= 12.5 um, h/d >= 5.5",
          _cpu_share_of_corner_cases),
    Claim("this machine against the cost law's median machine, 2026-12-04 and the fed A/B (prose)",
          "this machine runs {}-{}x slower than the cost law's median machine",
          MAIN_JOB + "stopped.json cpu_hours / cpu_hours_modelled; docs/case_cost/README.md prose ('ran 2.1x "
          "slower than the law's median machine')",
          lambda d: [_stop(d, "2026-12-04")["cpu_hours"] / _stop(d, "2026-12-04")["cpu_hours_modelled"],
                     _prose(d / "case_cost" / "README.md", "this machine ran {}x slower than the law's")[0]]),
    Claim("fidelity correction study: h/d range, cases", "points at h/d {}-{}, two seeds, {} cases",
          "docs/fidelity/correction/pairs.csv h_over_d; cases.csv rows", _correction_study),
    Claim("`smoke` row (2026-12-02)",
          "| `smoke` | {} s / {} s (2026-12-02: {}x cheaper than `reference` then) | {} % / {} % | MFR and PD {}-{} %",
          "docs/fidelity/presets.csv (smoke): cpu_s_median, cpu_s_max, cost_ratio_to_reference, "
          "mfr/pd_mean_abs_rel_error; per_point.csv: RMS of the seed CV",
          lambda d: [*_preset_row(d, "smoke"),
                     *(100 * _preset(d / "fidelity" / "presets.csv", "smoke")[[
                         "mfr_mean_abs_rel_error", "pd_mean_abs_rel_error"]].to_numpy(float))]),
    Claim("`fast` row (2026-12-02)",
          "| `fast` | {} s / {} s (2026-12-02: {}x cheaper then) | {} % / {} % | MFR {} % low",
          "docs/fidelity/presets.csv (fast); per_point.csv: RMS of the seed CV",
          lambda d: [*_preset_row(d, "fast"),
                     100 * _preset(d / "fidelity" / "presets.csv", "fast")["mfr_mean_abs_rel_error"]]),
    Claim("`default` row (2026-12-04)",
          "| `default` | **{} s / {} s** ({}x cheaper than `reference`) | {} % / {} % | **x{} ({}-{}) / x{} ({}-{})**",
          "docs/fidelity/correction/presets.csv (default): cpu_s_median/max; correction.json cpu_ratio, "
          "factor, mean_95; per_point.csv: RMS of the seed CV",
          lambda d: (lambda r: [r[0], r[1], _json(d / "fidelity" / "correction" / "correction.json")["cpu_ratio"],
                                r[2], r[3], _factor(d, "mfr")["factor"], *_factor(d, "mfr")["mean_95"],
                                _factor(d, "pd")["factor"], *_factor(d, "pd")["mean_95"]])(
              _corrected_row(d, "default"))),
    Claim("`reference` row (2026-12-04)", "| `reference` | {} s / {} s | {} % / {} % ({} seeds)",
          "docs/fidelity/correction/presets.csv (reference); per_point.csv: RMS of the seed CV, cases per point",
          lambda d: [*_corrected_row(d, "reference"),
                     _csv(d / "fidelity" / "correction" / "per_point.csv")["cases"].max()]),
    Claim("adhesion: CPU against dry; x1000 below x10 (coarse, fine); x100 below x10; CPU of x100, x10",
          "costs **{}x** the dry scene's (median {} s against {} s, max {} s against {} s). Density scaling is no "
          "longer free: with the surface energy scaled to keep the Bond number, x1000 reads MFR **{} % (d 45 um) to "
          "{} % (d 15 um) below density x10** (x100: {}-{} %, {}x the CPU of x1000; x10: {}x)",
          "docs/adhesion/scaling_cases.csv: geometric mean over points of the arms' mean CPU ratio; median/max "
          "cpu_time; per point (x10 - arm) / x10 of the mean MFR",
          _adhesion),
    Claim("size distribution: CPU against one size (D5-D95, D1-D99)",
          "costs **{}x (D50 45 um) to {}x (15 um)** the one-size case (median {} s against {} s, max {} s "
          "against {} s); cut at D1-D99, {}-{}x",
          "docs/size_distribution/cost_cases.csv: per point mean cpu_time ratio; median/max cpu_time",
          _size_distribution),
    Claim("overlap read every second step: CPU ratio, CI, pairs",
          "**{}x the CPU per case** (95 % CI {}-{}; {} pairs",
          "docs/case_cost/overlap_stride.csv: geometric mean of stride / every_step cpu_time, normal 95 %",
          _overlap_stride),
    Claim("a smaller heap: CPU at the wide point and the corner, MFR shift at the corner",
          "a heap of 3 h^2 ({}-{}x the CPU, MFR +{}, SE {}, at h/d {})",
          "docs/heap_size/cases.csv (rough, finished): median cpu_time 3 / 4.7 h^2 at the corner and the wide point; "
          "corner mean MFR 3 - 4.7 h^2",
          _heap_size),
    Claim("issue 31's benchmark: CPU at the seven points, the corner, over the box",
          "costs {}x the CPU at the seven points ({}-{}), {}x at the corner ({}-{}), **{}x over the box** ({}-{})",
          "docs/case_cost/final_summary.md, final_corner_summary.md (1 / arm-over-shipped); cost_map.json mean_ratio",
          _issue31),
    Claim("`default` per case over the box (cost law, this machine) and in the dry main job",
          "median {} s, max {} s (max / median {}; the main job of 2026-12-04: {} s, {} s, {})",
          "docs/case_cost/cost_map.json (shipped, default, this machine): median, max, max_over_median; "
          + MAIN_JOB + "cases.csv cpu_time median, max",
          _cost_map_default),
    Claim("the published study: distinct cases, CPU hours", "the maps that converged ({} cases, {} CPU hours)",
          "docs/study/cases_*.csv and *_gap_seeds.csv: distinct case_id, sum of cpu_time / 3600", _study),
    Claim("issue 31's benchmark: MFR shift's chi-square", "MFR reads higher (chi-square {} over {} points, p {})",
          "docs/case_cost/final_summary.md: issue31_start MFR chi-square line", _issue31_mfr),
]


def check(readme: str, docs: Path, claims: Sequence[Claim] = CLAIMS) -> list[Row]:
    """Every claim's numbers as README states them against the numbers derived from docs/.

    Parameters
    ----------
    readme : str
        README.md's text.
    docs : pathlib.Path
        The published results' folder (the repository's docs/).
    claims : sequence of Claim, optional
        The claims to check (default: all of README's that a table holds).

    Returns
    -------
    list of Row
        One row per number: ``status`` "ok" when the derived number rounds to the stated one
        (within ``tolerance(stated)``), "MISMATCH" when not, "NOT FOUND" (one row per claim) when
        README no longer has the phrase.
    """
    text = " ".join(readme.split())
    rows = []
    for claim in claims:
        derived = [(float(x[0]), float(x[1])) if isinstance(x, tuple) else (float(x), 0.0) for x in claim.derive(docs)]
        match = phrase_regex(claim.phrase).search(text)
        if match is None:
            rows.append(Row(claim.label, None, math.nan, math.nan, "NOT FOUND", claim.source))
            continue
        for i, (stated, (value, carried)) in enumerate(zip(match.groups(), derived)):
            tol = tolerance(stated) + carried
            ok = math.isfinite(value) and abs(value - float(stated)) <= tol
            label = claim.label if len(derived) == 1 else f"{claim.label} [{i + 1}]"
            rows.append(Row(label, stated, value, tol, "ok" if ok else "MISMATCH", claim.source))
    return rows


def report_text(rows: Sequence[Row]) -> str:
    """The check as lines to read: status, README's number, the derived one, what it is, its source.

    Parameters
    ----------
    rows : sequence of Row
        The result of ``check``.

    Returns
    -------
    str
        One line per number, sources once per claim, and a last line counting mismatches.
    """
    lines, last_source = [], None
    for r in rows:
        if r.source != last_source:
            lines.append(f"  from {r.source}")
            last_source = r.source
        derived = "-" if not math.isfinite(r.derived) else f"{r.derived:.{_decimals(r.stated) + 2}f}"
        lines.append(f"{r.status:9s} README {r.stated or '-':>8s}  derived {derived:>12s}  {r.label}")
    bad = sum(r.status != "ok" for r in rows)
    lines.append(f"{len(rows)} numbers, {bad} not matching or not found")
    return "\n".join(lines) + "\n"


def _decimals(stated: str | None) -> int:
    return len(stated.split(".")[1]) if stated and "." in stated else 0
