"""The numbers README.md states (and the guide, where it states what is current), re-derived from
the published tables under docs/ and the shipped config.yaml (issues 52, 65).

Each claim is a phrase of a page (README.md unless it names another) with ``{}`` where a number
stands, the tables it comes from (file, column, statistic) and a function that computes those
numbers from them. A stated number holds when the derived one rounds to it: the tolerance is half a
unit of its last printed digit (the page's rounding), so "1.41" holds 1.405-1.415 and "23" holds
22.5-23.5. A phrase no longer on its page is reported as not found (the claim then needs its new
wording here). A few numbers are in no table, only in the prose of a published page (this
machine's speed on other days): those are checked against that page's text, and say so.

The front page's numbers describe the shipped product: the run ``docs/main_job/run_2026-12-07e``
(the main job on the shipped scene from a clean clone), its replay and the config; the history is
in docs/CHANGELOG.md, which no claim reads. ``tools/readme_numbers.py`` prints the check;
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

import pandas as pd

NUMBER = r"([-+]?\d+(?:\.\d+)?)"


@dataclass(frozen=True)
class Claim:
    """One phrase of a page with its numbers (``{}``), their source and their derivation."""

    label: str
    phrase: str
    source: str
    derive: Callable[[Path], Sequence]  # per number a float, or (float, error it carries beyond the page's rounding)
    page: str = "README.md"  # the page that states it, relative to the repository


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


@cache
def _config(docs: Path) -> dict:
    """The shipped config.yaml (the repository's, beside docs/)."""
    import yaml

    return yaml.safe_load((docs.parent / "config.yaml").read_text())


def _prose(path: Path, phrase: str) -> list[float]:
    """Numbers a published page states in its prose (for numbers no table holds)."""
    match = phrase_regex(phrase).search(" ".join(path.read_text().split()))
    return [float(x) for x in match.groups()] if match else [math.nan] * phrase.count("{}")


def _run(docs: Path, day: str) -> Path:
    return docs / "main_job" / f"run_{day}"


def _stop(docs: Path, day: str) -> dict:
    return _json(_run(docs, day) / "stopped.json")


SHIPPED = "2026-12-07e"  # the shipped run: the main job on the shipped scene and config, from a clean clone
SHIPPED_RUN = f"docs/main_job/run_{SHIPPED}/"
SETUP_S = 47  # s, the set-up before the run's first job (the command at 18:16:43, the run's log from 18:17:30.1)


def _shipped_stop(docs: Path) -> list[float]:
    """Cases, usable, CPU h measured and modelled, map error of MFR and PD at the stop, tolerance."""
    s = _stop(docs, SHIPPED)
    t = s["criteria"]["at_this_batch"]["map_error"]["targets"]
    return [s["n"], s["usable"], s["cpu_hours"], s["cpu_hours_modelled"],
            t["mfr"]["estimate"], t["pd"]["estimate"], t["mfr"]["tolerance"]]


def _shipped_validation(docs: Path) -> list[float]:
    """The map model's (GP) CV RMSE over one run's noise SD and its 95 % intervals' coverage, MFR and PD."""
    m = _csv(_run(docs, SHIPPED) / "surrogate_metrics.csv")
    g = m[m["model"] == "gp"].set_index("target")
    return [g.loc["mfr", "rmse_over_noise"], g.loc["pd", "rmse_over_noise"], g.loc["mfr", "coverage"], g.loc["pd", "coverage"]]


def _loop(docs: Path) -> list[float]:
    """The config's loop: start, batch, tolerance (MFR; PD's must equal it), fewest stop cases, budget, CPU budget."""
    c = _config(docs)["converge"]
    tol = c["map_error"]["tolerance"]
    if tol["mfr"] != tol["pd"]:
        raise ValueError("the README states one tolerance for MFR and PD")
    return [c["start"], c["batch"], tol["mfr"], c["min_stop_cases"], c["budget"], c["cpu_budget_h"]]


def _run_ran_the_config(docs: Path, what: list[float]) -> list[float]:
    """``what`` (numbers of the config's loop) if the shipped run's settings are the config's, else NaN."""
    shipped, config = _stop(docs, SHIPPED)["settings"], _config(docs)["converge"]
    same = all(shipped[k] == config[k] for k in ("start", "batch", "budget", "cpu_budget_h", "min_stop_cases", "map_error"))
    return what if same else [math.nan] * len(what)


def _bond(docs: Path) -> list[float]:
    """The granular Bond number (DMT pull-off 4 pi gamma R*, R* = R/2 for equal spheres, over a sphere's
    weight) at the smallest and the largest d of the config's range."""
    c = _config(docs)
    m, (lo, hi) = c["material"], (c["ranges"]["d_um"]["min"], c["ranges"]["d_um"]["max"])

    def bond(d_um: float) -> float:
        r = d_um * 1e-6 / 2
        return 2 * math.pi * m["surface_energy_j_m2"] * r / (m["density_kg_m3"] * 4 / 3 * math.pi * r ** 3 * m["gravity_m_s2"])
    return [lo, bond(lo), bond(hi), hi]


def _bounds(docs: Path) -> list[float]:
    d = _config(docs)["decisions"]
    return [d["bounds"]["coverage"]["min"], d["bounds"]["thickness_ratio"]["min"], d["confidence"]]


def _recommendation(docs: Path, powder: str, kind: str = "fastest") -> pd.Series:
    r = _csv(_run(docs, SHIPPED) / "recommendations.csv")
    return r[(r["powder"] == powder) & (r["kind"] == kind)].iloc[0]


def _fine(docs: Path) -> list[float]:
    """`fine`'s powder (f, d), its fastest setting's probability, h, v (beyond the data), the best within it."""
    r = _recommendation(docs, "fine")
    if not (r["status"] == "beyond_data_only" and bool(r["beyond_data"])):
        return [math.nan] * 6
    return [r["f_low"], r["d_um_low"], r["probability"], r["h_um"], r["v_mm_s"], r["best_probability_in_data"]]


def _analyses_written(docs: Path) -> float:
    """Minutes from the command to the last of the maps, decisions and explorer page (the shipped run)."""
    t = _csv(_run(docs, SHIPPED) / "timeline.csv")
    return float(t[t["rule"].isin(["maps", "decide", "explorer"])]["end_min"].max()) + SETUP_S / 60


def _trend(docs: Path, day: str) -> list[float]:
    """Mean flow-trend z of a main job's cases and its SE."""
    z = _csv(_run(docs, day) / "cases.csv")["flow_trend_z_batch"].dropna()
    return [float(z.mean()), float(z.std(ddof=1) / math.sqrt(len(z)))]


def _exact_ci(k: int, n: int) -> tuple[float, float]:
    """The 95 % exact (Clopper-Pearson) interval of k successes in n, as the replay states it
    (spreadlab.experiments.replay.honesty: scipy's binomtest)."""
    from scipy.stats import binomtest

    ci = binomtest(k, n).proportion_ci(0.95, method="exact")
    return ci.low, ci.high


def _batch8_adhesive(docs: Path) -> list[float]:
    conv = _config(docs)["converge"]
    st = _csv(docs / "replay" / "adhesive" / "batch8" / "stops.csv")
    st = st[(st["design"] == f"active_per_cpu_b{conv['batch']}") & (st["rule"] == "bare estimate")
            & (st["margin"].astype(float) == float(conv["map_error"]["margin"]))]
    stops = st[st["stopped"].astype(bool)]
    k, n = int(stops["true_within"].astype(bool).sum()), len(stops)
    return [conv["map_error"]["margin"], conv["batch"], conv["min_stop_cases"], k, n, len(st), *_exact_ci(k, n)]


def _replay_steady_window(docs: Path) -> list[float]:
    """The shipped loop's replay on the steady window's truth: stops within the tolerance, replays, 95 % CI."""
    st = _csv(docs / "replay" / "adhesive" / "steady_window" / "stops_margin1.csv")
    k, n = int(st["true_within"].astype(bool).sum()), len(st)
    return [k, n, *_exact_ci(k, n)]


def _arm_point_cpu_ratio(cases: pd.DataFrame, arm: str, base: str) -> pd.Series:
    """Per point, the mean CPU of an arm's finished cases over the base arm's."""
    m = cases[cases["status"] == "ok"].groupby(["arm", "point"])["cpu_time"].mean()
    return m[arm] / m[base]


def _adhesion_x1000_low(docs: Path) -> list[float]:
    """Density x1000's MFR below density x10's, in %, at d 45 um (coarse) and d 15 um (fine): per point
    (x10 - x1000) / x10 of the unflagged cases' mean MFR."""
    a = _csv(docs / "adhesion" / "scaling_cases.csv")
    ok = a[(a["status"] == "ok") & ~a["flagged"].astype(bool)]
    mfr = ok.groupby(["arm", "point"])["mfr"].mean()
    low = 100 * (mfr["adh_x10"] - mfr["adh_x1000"]) / mfr["adh_x10"]
    return [low["coarse"], low["fine"]]


def _machine_speed(docs: Path) -> list[float]:
    """This machine's speed between days and within one (no table: the pages' prose): the same work's
    time on the days before run c, its largest spread between the study's sessions, the same cases
    70 min after the shipped run."""
    mj, study = docs / "main_job" / "README.md", docs / "guide" / "08-study.md"
    days = _prose(mj, "the same work took {}-{}x longer on the two days before")
    again = _prose(mj, "to the bit, at **{}x the CPU**")
    sessions = _prose(study, "speed differed by up to {}x between sessions")[0]
    return [days[0], sessions, *days, sessions, *again, _prose(mj, "The same run again, {} min later")[0]]


def _guide3_replays(docs: Path) -> list[float]:
    """The shipped loop on the adhesive truth (stopped, replays, honest, stops, CI, median and p90 cases and
    modelled CPU h) and on the shipped run's truth (honest, replays, CI, stops at 56 of them, CPU h median, p90)."""
    conv = _config(docs)["converge"]
    st = _csv(docs / "replay" / "adhesive" / "batch8" / "stops.csv")
    st = st[(st["design"] == f"active_per_cpu_b{conv['batch']}") & (st["rule"] == "bare estimate")
            & (st["margin"].astype(float) == float(conv["map_error"]["margin"]))]
    a = st[st["stopped"].astype(bool)]
    k = int(a["true_within"].astype(bool).sum())
    sw = _csv(docs / "replay" / "adhesive" / "steady_window" / "stops_margin1.csv")
    b = sw[sw["stopped"].astype(bool)]
    kb = int(b["true_within"].astype(bool).sum())
    return [len(a), len(st), k, len(a), *_exact_ci(k, len(a)), a["n"].median(), a["n"].quantile(0.9),
            a["cpu_h"].median(), a["cpu_h"].quantile(0.9),
            kb, len(sw), *_exact_ci(kb, len(b)), int((b["n"] == conv["min_stop_cases"]).sum()), len(sw),
            conv["min_stop_cases"], b["cpu_h"].median(), b["cpu_h"].quantile(0.9)]


def _powder(docs: Path, powder: str, kind: str = "fastest") -> list[float]:
    """A powder's best setting in the shipped run: h, v, coverage and thickness / h (low, high over its range)."""
    r = _recommendation(docs, powder, kind)
    return [r["h_um"], r["v_mm_s"], r["coverage_mean_low"], r["coverage_mean_high"],
            r["thickness_ratio_mean_low"], r["thickness_ratio_mean_high"]]


def _below(value: float, bound: float) -> float:
    """``bound`` when ``value`` is below it (a "below 0.001" claim), else NaN."""
    return bound if value < bound else math.nan


README = "README.md"
GUIDE3, GUIDE5 = "docs/guide/03-convergence.md", "docs/guide/05-decisions.md"
GUIDE_INDEX = "docs/guide/README.md"

CLAIMS: list[Claim] = [
    Claim("front figure: the Bond number at the range's smallest and largest d",
          "Bond number {} at d = {} um to {} at {} um",
          "config.yaml material (surface energy, density, gravity), ranges.d_um: 2 pi gamma R / (4/3 pi R^3 rho g)",
          lambda d: (lambda b: [b[1], b[0], b[2], b[3]])(_bond(d))),
    Claim("front figure: the machine map's powder point, surface energy, the preset's density scale",
          "The machine map (f = {}, d = {} um) of the shipped run, [run_2026-12-07e](docs/main_job/README.md) "
          "({} cases from a clean clone on 2026-12-07): **adhesive powder** (DMT, surface energy {}e-{} J/m^2,",
          "config.yaml maps.machine f, d_um; material.surface_energy_j_m2 as mantissa and exponent; "
          + SHIPPED_RUN + "stopped.json: n",
          lambda d: (lambda c, e: [c["maps"]["machine"]["f"], c["maps"]["machine"]["d_um"], _stop(d, SHIPPED)["n"],
                                   e / 10 ** round(math.log10(e)), -round(math.log10(e))])(
              _config(d), _config(d)["material"]["surface_energy_j_m2"])),
    Claim("front figure: the `default` preset's density scale", "at **fidelity `default`: density x{}, not corrected",
          "config.yaml presets.default.density_scale; fidelity_correction applies to surface energy 0 only",
          lambda d: [_config(d)["presets"]["default"]["density_scale"]
                     if _config(d)["fidelity_correction"]["surface_energy_j_m2"] != _config(d)["material"]["surface_energy_j_m2"]
                     else math.nan]),
    Claim("the main job's loop (config converge:, as the shipped run ran it)",
          "The main job runs {} LDS cases at the `default` preset, then batches of {} (half continuing the LDS "
          "sequence, half where the map is least sure per CPU-second) until the map's own error is within {} "
          "(MFR and PD, from {} cases on) or {} cases or {} modelled CPU hours",
          "config.yaml converge: start, batch, map_error.tolerance, min_stop_cases, budget, cpu_budget_h; "
          + SHIPPED_RUN + "stopped.json settings equal to them", lambda d: _run_ran_the_config(d, _loop(d))),
    Claim("the shipped run: cases, usable, CPU h measured and modelled, map error MFR, PD, tolerance",
          "criteria met at {} cases ({} usable, {} CPU h measured, {} modelled); map error MFR {} and PD {} "
          "against the {} tolerance",
          SHIPPED_RUN + "stopped.json: n, usable, cpu_hours, cpu_hours_modelled, "
          "criteria.at_this_batch.map_error.targets.*.estimate, tolerance", _shipped_stop),
    Claim("the shipped run's validation: CV RMSE over noise (MFR, PD), 95 % coverage (MFR, PD)",
          "RMSE is {}x one run's noise SD for MFR and {}x for PD, its 95 % intervals cover {} and {}",
          SHIPPED_RUN + "surrogate_metrics.csv (gp): rmse_over_noise, coverage", _shipped_validation),
    Claim("the shipped run: mean flow-trend z (SE)", "mean flow-trend z is +{} (SE {})",
          SHIPPED_RUN + "cases.csv: flow_trend_z_batch, mean and SE", lambda d: _trend(d, SHIPPED)),
    Claim("the adhesive replay of the shipped loop: margin, batch, fewest cases, stops honest, stops, replays, 95 % CI",
          "(no DEM; margin {}, batches of {}, stops from {} cases: {} of {} stops within the tolerance on {} "
          "replays, 95 % CI {}-{}",
          "config.yaml converge; docs/replay/adhesive/batch8/stops.csv (design of the config's batch, bare "
          "estimate at its margin): true_within, stopped rows, rows, Clopper-Pearson", _batch8_adhesive),
    Claim("the shipped loop's replay on the shipped scene's truth: honest stops, replays, 95 % CI",
          "on the shipped scene's truth {} of {}, {}-{};",
          "docs/replay/adhesive/steady_window/stops_margin1.csv: true_within, Clopper-Pearson", _replay_steady_window),
    Claim("the shipped layer bounds and confidence", "(coverage >= {}, thickness >= {} h) with P >= {}",
          "config.yaml decisions: bounds.coverage.min, bounds.thickness_ratio.min, confidence", _bounds),
    Claim("the shipped run's recommendation for `fine`: powder, P beyond the data at (h, v), best within",
          "`fine` (f {}, d {} um) reaches P {} only beyond the data (h {} um, v {} mm/s), {} at best within it",
          SHIPPED_RUN + "recommendations.csv (fine, fastest; status beyond_data_only): f_low, d_um_low, "
          "probability, h_um, v_mm_s, best_probability_in_data", _fine),
    Claim("the shipped run: minutes to the maps, decisions and explorer; the set-up in it",
          "explorer page **{} min** after it started (set-up {} s included)",
          SHIPPED_RUN + "timeline.csv: the last end_min of maps, decide, explorer + the set-up (47 s, the run's log)",
          lambda d: [_analyses_written(d), SETUP_S]),
    Claim("the shipped run: the whole run's minutes", "the surrogate's validation last, took {} min",
          SHIPPED_RUN + "timeline.json: wall_s / 60, + the set-up before the first job (47 s, the run's log)",
          lambda d: [(_json(_run(d, SHIPPED) / "timeline.json")["wall_s"] + SETUP_S) / 60]),
    Claim("this machine's speed between days and within one (no table: the pages' prose)",
          "This machine's speed moves {}-{}x between days (the same cases took {}-{}x longer on two other days, "
          "up to {}x between the study's sessions; the shipped run's cases ran at {}x the CPU only {} min later",
          "docs/main_job/README.md prose (run c: 'took 1.3-1.5x longer on the two days before'; the same run "
          "again: '1.29x the CPU', '70 min later'); docs/guide/08-study.md prose ('up to 2x between sessions')",
          _machine_speed),
    Claim("density x1000 against x10: MFR low at d 45 um and d 15 um",
          "at density x1000 MFR reads {} % (d 45 um) to {} % (d 15 um) below density x10",
          "docs/adhesion/scaling_cases.csv: per point (x10 - x1000) / x10 of the mean MFR", _adhesion_x1000_low),
    Claim("guide 3: the main job's loop (config converge:)",
          "(`converge:`): {} LDS cases at the `default` preset, then batches of {}, half continuing the LDS "
          "sequence and half where the map is least sure per planned CPU-second, until **the map's own error "
          "is within {} (MFR and PD)**, judged from {} cases on, or the budget is spent ({} cases or **{} "
          "modelled CPU hours**)",
          "config.yaml converge (the shipped run's settings equal to them)", lambda d: _run_ran_the_config(d, _loop(d)),
          GUIDE3),
    Claim("guide 3: the shipped run's stop", "density x{}) stopped at {} cases, its map error MFR {} and PD {}.",
          "config.yaml presets.default.density_scale; " + SHIPPED_RUN + "stopped.json",
          lambda d: [_config(d)["presets"]["default"]["density_scale"], *(lambda x: [x[0], x[4], x[5]])(_shipped_stop(d))],
          GUIDE3),
    Claim("guide 3: the shipped loop's replays (adhesive truth; the shipped run's truth)",
          "{} of {} replays stopped, **{} of {} within 0.02 (95 % CI {}-{})**, at {} cases (median; p90 {}) and {} "
          "modelled CPU h (p90 {}). On a truth fitted on the shipped run's usable cases (run_2026-12-07e, the "
          "shipped scene; pre-registered, no seed chose the rule): **{} of {} within 0.02 (95 % CI {}-{})**, {} of "
          "{} at {} cases, {} modelled CPU h (median; p90 {})",
          "docs/replay/adhesive/batch8/stops.csv (the config's design and margin), "
          "docs/replay/adhesive/steady_window/stops_margin1.csv: stopped, true_within, n, cpu_h; Clopper-Pearson",
          _guide3_replays, GUIDE3),
    Claim("guide 3: the shipped run's minutes to its maps, the same cases' CPU 70 min later",
          "wrote its maps {} min after the command on this machine; the same cases ran at {}x the CPU {} min later",
          SHIPPED_RUN + "timeline.csv (+ the set-up); docs/main_job/README.md prose",
          lambda d: [_analyses_written(d), *_machine_speed(d)[5:]], GUIDE3),
    Claim("guide 5: the bounds and confidence", "with the shipped bounds (coverage >= {}, layer thickness >= {} h) at {} %",
          "config.yaml decisions", lambda d: (lambda b: [b[0], b[1], 100 * b[2]])(_bounds(d)), GUIDE5),
    Claim("guide 5: `fine` in the shipped run",
          "`fine` (f {}, d {} um): at best P {} within the data; only beyond it does a setting reach P {}, the "
          "fastest h {} um, v {} mm/s (coverage {}, thickness {} h)",
          SHIPPED_RUN + "recommendations.csv (fine, fastest)",
          lambda d: (lambda f, p: [f[0], f[1], f[5], f[2], f[3], f[4], p[2], p[4]])(_fine(d), _powder(d, "fine")), GUIDE5),
    Claim("guide 5: `medium_range` in the shipped run",
          "`medium_range` (f {}-{}, d {}-{} um, the whole range): P below {} everywhere in the data; at its best "
          "setting, h {} um, v {} mm/s, coverage {}-{} and thickness {}-{} h",
          SHIPPED_RUN + "recommendations.csv (medium_range): f, d range, best_probability_in_data, h, v, coverage, thickness",
          lambda d: (lambda r, p: [r["f_low"], r["f_high"], r["d_um_low"], r["d_um_high"],
                                   _below(r["best_probability_in_data"], 0.001), *p])(
              _recommendation(d, "medium_range"), _powder(d, "medium_range")), GUIDE5),
    Claim("guide 5: `coarse` in the shipped run",
          "`coarse` (f {}, d {} um): P below {}; at its best, h {} um, v {} mm/s, coverage {} and thickness {} h",
          SHIPPED_RUN + "recommendations.csv (coarse)",
          lambda d: (lambda r, p: [r["f_low"], r["d_um_low"], _below(r["best_probability_in_data"], 0.001),
                                   p[0], p[1], p[2], p[4]])(_recommendation(d, "coarse"), _powder(d, "coarse")), GUIDE5),
    Claim("guide 5: density x1000 against x10", "MFR reads {}-{} % below density x10",
          "docs/adhesion/scaling_cases.csv", _adhesion_x1000_low, GUIDE5),
    Claim("guide index: the shipped run", "rough floor; {} cases, maps at {} min)",
          SHIPPED_RUN + "stopped.json n; timeline.csv (+ the set-up)",
          lambda d: [_stop(d, SHIPPED)["n"], _analyses_written(d)], GUIDE_INDEX),
]


def check(readme: str, docs: Path, claims: Sequence[Claim] | None = None) -> list[Row]:
    """Every claim's numbers as one page states them against the numbers derived from docs/.

    Parameters
    ----------
    readme : str
        The page's text (README.md's by default).
    docs : pathlib.Path
        The published results' folder (the repository's docs/; the config beside it).
    claims : sequence of Claim, optional
        The claims to check (default: README.md's of ``CLAIMS``).

    Returns
    -------
    list of Row
        One row per number: ``status`` "ok" when the derived number rounds to the stated one
        (within ``tolerance(stated)``), "MISMATCH" when not, "NOT FOUND" (one row per claim) when
        README no longer has the phrase.
    """
    claims = [c for c in CLAIMS if c.page == README] if claims is None else claims
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


def check_pages(root: Path, docs: Path | None = None, claims: Sequence[Claim] = CLAIMS) -> list[Row]:
    """Every claim against its own page under ``root`` (README.md, the guide's pages).

    Parameters
    ----------
    root : pathlib.Path
        The repository (its pages and its docs/).
    docs : pathlib.Path, optional
        The published results' folder (default ``root / "docs"``).
    claims : sequence of Claim, optional
        The claims to check (default: all).

    Returns
    -------
    list of Row
        ``check``'s rows page by page, README.md's first; a guide page's labels start with its name.
    """
    docs = root / "docs" if docs is None else docs
    pages = sorted({c.page for c in claims}, key=lambda p: (p != README, p))
    rows = []
    for page in pages:
        mine = [c for c in claims if c.page == page]
        if page != README:
            mine = [Claim(f"{Path(page).stem}: {c.label}", c.phrase, c.source, c.derive, c.page) for c in mine]
        rows += check((root / page).read_text(), docs, mine)
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
