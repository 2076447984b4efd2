#!/usr/bin/env python
"""The truth ladder's analysis, as pre-registered in docs/truth/README.md (issue 64): each rung's
bias against the stiffest measured per point, the x1_E10 = x10 equivalence, the truth level, which
variable (Bond number, or the work of separation over a sphere's kinetic energy at the blade speed)
collapses the bias, and the surface-energy exponent p* fitted on the fit points.

    .venv/bin/python tools/truth_ladder_report.py --cases docs/truth/ladder_cases.csv \
        --out docs/truth/ladder_analysis.md --figure docs/truth/ladder

Reads the table benchmarks/truth_ladder.py writes; the numbers it states are what it measured so far
(a rung or point not yet run is said to be missing).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from spreadmap.design import NAMES, TARGETS  # mfr, pd
from spreadmap.files import write_text_atomically
from spreadmap.table import usable_cases

RUNGS = ["x1000", "x100", "x10", "x1"]  # cheapest first; the ladder toward the stiff limit
STIFFEST = ["x1_316L", "x1"]            # the reference at a point: the first of these measured there
FIT_POINTS = ["coarse", "medium", "fine"]
HELD_OUT = ["slow", "corner"]
EXPONENT_ARMS = {1.0: "x1000", 0.8: "x1000_p0.8", 0.6: "x1000_p0.6"}
POOLED_MARGIN = 0.01   # the truth level's pooled mean bias: 90 % CI inside +- this
Z_BOUND = 2.0


def cell_stats(cases: pd.DataFrame) -> pd.DataFrame:
    """Per (point, arm): seeds, mean and SE (from the seeds' spread) of each target, the median CPU and
    the point's design and physics columns; usable cases only (flagged ones counted)."""
    good = usable_cases(cases, TARGETS)
    rows = []
    for (point, arm), group in cases.groupby(["point", "arm"], sort=False):
        ok = good[(good["point"] == point) & (good["arm"] == arm)]
        row = {"point": point, "arm": arm, "seeds": len(ok), "not_usable": len(group) - len(ok),
               "cpu_median": float(np.median(group["cpu_time"])), **{k: group[k].iloc[0] for k in
               (*NAMES, "density_scale", "young_pa", "surface_energy")}}
        for t in TARGETS:
            x = ok[t].to_numpy(float)
            row[t] = x.mean() if len(x) else math.nan
            row[f"{t}_se"] = x.std(ddof=1) / math.sqrt(len(x)) if len(x) > 1 else math.nan
        rows.append(row)
    return pd.DataFrame(rows)


def work_over_kinetic(row, poisson: float = 0.3, density: float = 7980.0) -> float:
    """A pair's DMT work of separation from equilibrium, W = (3/5) F_ad delta_eq (F_ad = 4 pi gamma R*,
    delta_eq where Hertz's (4/3) E* sqrt(R*) delta^(3/2) = F_ad), at the rung's effective modulus
    E/S and surface energy gamma_applied/S, over a sphere's kinetic energy at the blade speed
    (real density): the dimensionless stickiness of a slow encounter."""
    # the scene applies the case's surface_energy x S with every mass x S: the real-density powder at
    # surface energy `surface_energy` and modulus E / S
    scale = float(row["density_scale"])
    gamma, young = float(row["surface_energy"]), float(row["young_pa"]) / scale
    radius = 0.5 * float(row["d_um"]) * 1e-6
    r_star, e_star = radius / 2.0, young / (2.0 * (1.0 - poisson ** 2))
    pull_off = 4.0 * math.pi * gamma * r_star
    delta = (pull_off / (4.0 / 3.0 * e_star * math.sqrt(r_star))) ** (2.0 / 3.0)
    mass = density * math.pi / 6.0 * (2 * radius) ** 3
    kinetic = 0.5 * mass * (float(row["v_mm_s"]) * 1e-3) ** 2
    return 0.6 * pull_off * delta / kinetic


def biases(cells: pd.DataFrame) -> pd.DataFrame:
    """Each arm's difference from the stiffest arm measured at its point, per target, with its SE and z."""
    out = []
    for point, group in cells.groupby("point", sort=False):
        ref_arm = next((a for a in STIFFEST if (group["arm"] == a).any() and
                        group.loc[group["arm"] == a, "seeds"].iloc[0] >= 2), None)
        if ref_arm is None:
            continue
        ref = group[group["arm"] == ref_arm].iloc[0]
        for _, row in group.iterrows():
            if row["arm"] == ref_arm or row["seeds"] < 2:
                continue
            rec = {"point": point, "arm": row["arm"], "reference": ref_arm, "seeds": row["seeds"],
                   "ref_seeds": ref["seeds"]}
            for t in TARGETS:
                rec[f"{t}_bias"] = row[t] - ref[t]
                rec[f"{t}_se"] = math.hypot(row[f"{t}_se"], ref[f"{t}_se"])
                rec[f"{t}_z"] = rec[f"{t}_bias"] / rec[f"{t}_se"] if rec[f"{t}_se"] > 0 else math.nan
                rec[f"{t}_rel"] = rec[f"{t}_bias"] / ref[t]
            out.append(rec)
    return pd.DataFrame(out)


def pooled_interval(bias: pd.DataFrame, target: str, level: float = 0.90) -> tuple[float, float, float]:
    """The mean of the points' biases and its t interval, (mean, low, high). Its SE is the larger of
    the points' own SEs (sqrt(sum se^2) / n; the seeds' degrees of freedom) and the biases' spread
    over the points (their SD / sqrt(n); n - 1 degrees of freedom)."""
    b, se = bias[f"{target}_bias"].to_numpy(float), bias[f"{target}_se"].to_numpy(float)
    n = len(b)
    if n == 0:
        return math.nan, math.nan, math.nan
    from_ses = math.sqrt(np.sum(se ** 2)) / n
    from_spread = b.std(ddof=1) / math.sqrt(n) if n > 1 else 0.0
    if from_spread > from_ses:
        se_mean, dof = from_spread, n - 1
    else:
        se_mean, dof = from_ses, max(int((bias["seeds"] + bias["ref_seeds"] - 2).sum()), 1)
    half = stats.t.ppf(0.5 + level / 2, dof) * se_mean
    return float(b.mean()), float(b.mean() - half), float(b.mean() + half)


def truth_level(bias: pd.DataFrame, points: list[str]) -> tuple[str | None, list[str]]:
    """The cheapest rung within Z_BOUND SE of the stiffest at every point of `points` (MFR and PD) whose
    pooled bias has a 90 % CI inside +-POOLED_MARGIN; with the reasons each cheaper rung failed."""
    reasons = []
    for rung in RUNGS:
        here = bias[bias["point"].isin(points)]
        if set(here.groupby("point")["reference"].first()) == {rung}:
            return rung, reasons  # the stiffest measured itself
        rows = here[here["arm"] == rung]
        missing = sorted(set(points) - set(rows["point"]))
        if missing:
            reasons.append(f"{rung}: not measured at {', '.join(missing)}")
            continue
        far = [f"{r.point} {t} z {getattr(r, t + '_z'):+.1f}" for r in rows.itertuples() for t in TARGETS
               if abs(getattr(r, t + "_z")) > Z_BOUND]
        wide = [f"{t} pooled {m:+.4f} (90 % CI {lo:+.4f} to {hi:+.4f})" for t in TARGETS
                for m, lo, hi in [pooled_interval(rows, t)] if lo < -POOLED_MARGIN or hi > POOLED_MARGIN]
        if not far and not wide:
            return rung, reasons
        reasons.append(f"{rung}: " + "; ".join(far + wide))
    return None, reasons


def fitted_exponent(cells: pd.DataFrame, truth: str) -> tuple[float, pd.DataFrame]:
    """p* minimising the sum over the fit points of ((MFR(p) - MFR_truth) / SE)^2, MFR(p) linear
    through the exponent arms measured there, on p in [0.5, 1] by 0.01; nan when no fit point has
    two exponent arms and the truth."""
    grid = np.round(np.arange(0.5, 1.0001, 0.01), 2)
    total = np.zeros_like(grid)
    used = []
    for point in FIT_POINTS:
        here = cells[cells["point"] == point].set_index("arm")
        arms = [(p, a) for p, a in sorted(EXPONENT_ARMS.items()) if a in here.index and here.loc[a, "seeds"] >= 2]
        if len(arms) < 2 or truth not in here.index or here.loc[truth, "seeds"] < 2:
            continue
        ps = np.array([p for p, _ in arms])
        mfr = np.array([here.loc[a, "mfr"] for _, a in arms])
        se2 = np.array([here.loc[a, "mfr_se"] ** 2 for _, a in arms]).mean() + here.loc[truth, "mfr_se"] ** 2
        total += (np.interp(grid, ps, mfr) - here.loc[truth, "mfr"]) ** 2 / se2
        used.append(point)
    if not used:
        return math.nan, pd.DataFrame()
    return float(grid[int(np.argmin(total))]), pd.DataFrame({"p": grid, "chi2": total})


def collapse(bias: pd.DataFrame, cells: pd.DataFrame) -> dict:
    """R^2 of a least-squares line of each rung's relative MFR bias on log10 of the Bond number and
    on log10 of W/K, over every rung (density arms and exponent arms) and point."""
    rows = bias.merge(cells, on=["point", "arm"], suffixes=("", "_cell"))
    if len(rows) < 3:
        return {}
    rows["w_over_k"] = [work_over_kinetic(r) for _, r in rows.iterrows()]
    rows["bond"] = rows["surface_energy"] / rows["d_um"] ** 2  # the Bond number ~ gamma / d^2 (one density, g)
    out = {}
    for name in ("bond", "w_over_k"):
        x = np.log10(rows[name].to_numpy(float))
        if np.ptp(x) == 0:  # one Bond number (one point so far): no line to fit
            out[name] = {"r2": math.nan, "slope": math.nan, "n": len(rows)}
            continue
        fit = stats.linregress(x, rows["mfr_rel"].to_numpy(float))
        out[name] = {"r2": fit.rvalue ** 2, "slope": fit.slope, "n": len(rows)}
    out["rows"] = rows
    return out


def report(cases: pd.DataFrame) -> tuple[str, dict]:
    cells = cell_stats(cases)
    bias = biases(cells)
    lines = ["# The truth ladder, as measured so far", "",
             "`tools/truth_ladder_report.py` on `docs/truth/ladder_cases.csv` (the analysis pre-registered in "
             "README.md). Mean of the seeds ± SE from their spread; bias = arm - the stiffest arm measured at "
             "the point, with its SE and z.", "", "## Cells", "",
             "| point | arm | seeds (not usable) | MFR | PD | CPU s median |", "|---|---|---|---|---|---|"]
    for r in cells.itertuples():
        lines.append(f"| {r.point} | {r.arm} | {r.seeds} ({r.not_usable}) | {r.mfr:.4f} ± {r.mfr_se:.4f} | "
                     f"{r.pd:.4f} ± {r.pd_se:.4f} | {r.cpu_median:.0f} |")
    lines += ["", "## Bias against the stiffest measured", ""]
    if bias.empty:
        lines.append("No point has its stiffest rung (x1) measured with 2 seeds yet.")
    else:
        lines += ["| point | arm | against | MFR bias (z) | relative | PD bias (z) |", "|---|---|---|---|---|---|"]
        for r in bias.itertuples():
            lines.append(f"| {r.point} | {r.arm} | {r.reference} | {r.mfr_bias:+.4f} ± {r.mfr_se:.4f} ({r.mfr_z:+.1f}) | "
                         f"{100 * r.mfr_rel:+.1f} % | {r.pd_bias:+.4f} ± {r.pd_se:.4f} ({r.pd_z:+.1f}) |")
    here = cells.set_index(["point", "arm"])
    lines += ["", "## Equivalence: x1_E10 against x10", ""]
    eq_rows = [(p, here.loc[(p, "x1_E10")], here.loc[(p, "x10")]) for p in cells["point"].unique()
               if (p, "x1_E10") in here.index and (p, "x10") in here.index]
    for p, a, b in eq_rows:
        for t in TARGETS:
            d, se = a[t] - b[t], math.hypot(a[f"{t}_se"], b[f"{t}_se"])
            lines.append(f"- {p} {t}: x1_E10 - x10 = {d:+.4f} ± {se:.4f} (z {d / se:+.2f}): "
                         + ("equal within 2 SE" if abs(d) <= 2 * se else "NOT equal within 2 SE"))
    if not eq_rows:
        lines.append("Not measured yet.")
    points_with_ref = sorted(set(bias["point"])) if not bias.empty else []
    level, reasons = truth_level(bias, points_with_ref) if points_with_ref else (None, ["no point has x1 yet"])
    lines += ["", "## The truth level", "",
              f"Points with the stiffest rung measured: {', '.join(points_with_ref) or 'none'} "
              f"(of {', '.join(cells['point'].unique())}).",
              f"Cheapest rung within {Z_BOUND:g} SE of the stiffest at these points, pooled 90 % CI inside "
              f"±{POOLED_MARGIN}: **{level or 'none'}**" + (" (on these points only: not yet named)" if
                                                             len(points_with_ref) < 5 else "")]
    lines += [f"- {r}" for r in reasons]
    p_star, _ = fitted_exponent(cells, "x1")
    lines += ["", "## The surface-energy exponent fitted on the fit points", "",
              f"p* = {p_star:.2f} (x1000's applied surface energy gamma x 1000^p*; 1 keeps the Bond number, "
              "0.6 keeps x1's work of separation)" if math.isfinite(p_star) else
              "Not yet: needs two exponent arms and x1 at a fit point."]
    col = collapse(bias, cells) if not bias.empty else {}
    lines += ["", "## What collapses the bias", ""]
    if col:
        lines += [f"- relative MFR bias on log10 Bond number: R^2 {col['bond']['r2']:.2f} ({col['bond']['n']} rung-points)",
                  f"- on log10 W/K (work of separation at E/S over the kinetic energy at the blade speed): "
                  f"R^2 {col['w_over_k']['r2']:.2f}"]
    else:
        lines.append("Not yet: fewer than 3 rung-points with a reference.")
    return "\n".join(lines) + "\n", {"cells": cells, "bias": bias, "collapse": col, "level": level, "p_star": p_star}


def figure(result: dict, stem: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cells = result["cells"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    ax = axes[0]
    for point, group in cells[cells["arm"].isin(RUNGS)].groupby("point", sort=False):
        g = group.sort_values("density_scale")
        ax.errorbar(g["density_scale"], g["mfr"], yerr=1.96 * g["mfr_se"].fillna(0), marker="o", capsize=3,
                    label=f"{point} (d {g['d_um'].iloc[0]:g} um)")
    ax.set_xscale("log")
    ax.invert_xaxis()
    ax.set_xlabel("density scale S (the powder at E / S): toward the stiff limit ->")
    ax.set_ylabel("MFR (mean of seeds, 95 % CI)")
    ax.set_title("The ladder: MFR by rung (adhesive 316L model, rough floor)")
    ax.legend(fontsize=8)
    ax = axes[1]
    col = result["collapse"]
    if col:
        rows = col["rows"]
        for point, g in rows.groupby("point", sort=False):
            ax.errorbar(g["w_over_k"], 100 * g["mfr_rel"], yerr=196 * g["mfr_se"] / (g["mfr"] - g["mfr_bias"]),
                        marker="o", linestyle="none", capsize=3, label=point)
        ax.set_xscale("log")
        ax.axhline(0, color="0.5", lw=0.8)
        ax.set_xlabel("W / K: work of separation at E/S over a sphere's kinetic energy at v")
        ax.set_ylabel("MFR bias against the stiffest [%]")
        ax.set_title(f"Collapse: R^2 {col['w_over_k']['r2']:.2f} (on log Bond: {col['bond']['r2']:.2f})")
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "no rung-point with its stiffest reference yet", ha="center", transform=ax.transAxes)
        ax.set_axis_off()
    fig.tight_layout()
    paths = [stem.with_suffix(".png"), stem.with_suffix(".pdf")]
    for p in paths:
        fig.savefig(p, dpi=130)
    plt.close(fig)
    return paths


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", required=True)
    ap.add_argument("--out", help="the analysis (markdown)")
    ap.add_argument("--figure", help="the figure's path without suffix (.png and .pdf)")
    args = ap.parse_args(argv)
    cases = pd.read_csv(args.cases)
    text, result = report(cases)
    print(text)
    if args.out:
        write_text_atomically(Path(args.out), text)
    if args.figure:
        figure(result, Path(args.figure))
    return 0


if __name__ == "__main__":
    sys.exit(main())
