#!/usr/bin/env python3
"""Is the flow steady in a run's windows? The flow-trend z of published cases tables, re-derived from
their columns, per h/d band, and the steady flag's power on synthetic flows (docs/steady_window).

    .venv/bin/python tools/flow_trend_check.py [CASES_CSV ...] [--batches 8] [--power] [--draws 2000]

With no CASES_CSV: the main job's published runs (docs/main_job/run_2026-12-06/cases.csv, adhesive;
docs/main_job/run_2026-12-04/cases.csv, dry; docs/main_job/cases.csv, the dry loop of 2026-12-01).
Prints Markdown.

A cases table holds, per case, flow_trend (the flow's change between the window's halves over its
mean), flow_trend_z (that change in counting-noise SEs, 2c / sqrt(N)), mfr and mfr_sd_within (the
SD of the window's MFR from b batch means, SD(batch flows) / sqrt(b)). From these, per case:

* z_plain = flow_trend / (2 mfr_sd_within / mfr): the change over 2 SD(batches) / sqrt(b), with the
  plain SD of the batches. That SD holds the change itself (a difference D of the halves adds
  b D^2 / 4 to the batches' sum of squares), so |z_plain| <= sqrt(b - 1) (2.65 at b = 8) in every
  case: it can never pass a bound of 3.
* t_halves = z_plain sqrt((b - 2) / (b - 1 - z_plain^2)): the same change over the SE from the
  batches' scatter about their own half's mean (the sums of squares split exactly, within + b D^2 / 4),
  Student's t with b - 2 dof for a steady flow; z_halves its normal score (standard normal then).
  (mfr stands in for the series' mean flow, counted by sphere centres; b is taken as `--batches`
  for every case, though a case with fewer than 2b monitor intervals in its window had fewer.)

The steady flag (spreadmap.metrics.noise.flow_trend_batch_z, column flow_trend_z_batch) takes its SE
from the scatter about a quadratic plus a jump (b - 4 dof), which a table cannot give (it needs the
batch flows). Its residual sum of squares is at most the halves', so |t_flag| >= |t_halves|
sqrt((b - 4) / (b - 2)): a case whose bound passes the flag's is flagged for sure; of the others a
table cannot tell.

--power: the share of synthetic windows the flag (|z| > 3) catches, for a flow that falls or rises by
a given share between the halves (a step at the middle, or a linear ramp), with Poisson noise at the
default preset's window (~153 spheres) and the published runs' batch noise (c ~ 0.5: Poisson with
153 / c^2 spheres).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from spreadmap.metrics import flow_trend_batch_z
from spreadmap.metrics.noise import t_normal_score

ROOT = Path(__file__).resolve().parent.parent
TABLES = {"adhesive, run 2026-12-06": "docs/main_job/run_2026-12-06/cases.csv",
          "dry, run 2026-12-04": "docs/main_job/run_2026-12-04/cases.csv",
          "dry, loop of 2026-12-01": "docs/main_job/cases.csv"}
BANDS = ((1.0, 1.5), (1.5, 2.0), (2.0, 3.0), (3.0, 8.0))
BOUND = 3.0
# the default preset's window in the published runs: ~153 spheres passed ((c / target_cv)^2), 8 d at least
WINDOW_SPHERES = 153


def case_z(table: pd.DataFrame, batches: int = 8) -> pd.DataFrame:
    """Per finished case with the columns: h/d, the counting-noise z, z_plain, t_halves, z_halves and
    the bound on the steady flag's |t| (see the module's docstring)."""
    ok = table[table["status"] == "ok"].copy()
    for c in ("flow_trend", "flow_trend_z", "mfr", "mfr_sd_within"):
        ok[c] = pd.to_numeric(ok[c], errors="coerce")
    ok = ok[np.isfinite(ok[["flow_trend", "mfr", "mfr_sd_within"]]).all(axis=1)]
    b = batches
    z_plain = ok["flow_trend"] / (2.0 * ok["mfr_sd_within"] / ok["mfr"])
    t_halves = z_plain * np.sqrt((b - 2) / np.clip(b - 1 - z_plain ** 2, 1e-12, None))
    out = pd.DataFrame({"case_id": ok["case_id"], "h_over_d": ok["h_um"] / ok["d_um"],
                        "flow_trend": ok["flow_trend"], "z_counting": ok["flow_trend_z"], "z_plain": z_plain,
                        "t_halves": t_halves, "z_halves": [t_normal_score(t, b - 2) for t in t_halves],
                        "z_flag_at_least": [abs(t_normal_score(t * math.sqrt((b - 4) / (b - 2)), b - 4)) for t in t_halves],
                        "flagged_now": ok["flagged"].astype(bool), "flag_reason": ok["flag_reason"].astype("string").fillna("")})
    return out.reset_index(drop=True)


def moments(z: pd.Series) -> dict:
    """n, mean (SE), its z against 0 and two-sided p, SD (its SE), counts beyond +-BOUND."""
    z = z[np.isfinite(z)]
    n = len(z)
    mean, sd = float(z.mean()), float(z.std(ddof=1)) if n > 1 else math.nan
    se = sd / math.sqrt(n) if n > 1 else math.nan
    p = math.erfc(abs(mean / se) / math.sqrt(2)) if se > 0 else math.nan
    return {"n": n, "mean": mean, "se": se, "p_mean_0": p, "sd": sd, "sd_se": sd / math.sqrt(2 * (n - 1)) if n > 1 else math.nan,
            "below_-3": int((z < -BOUND).sum()), "above_+3": int((z > BOUND).sum())}


def band_summary(cases: pd.DataFrame, column: str) -> pd.DataFrame:
    """`moments` of one z column over all cases and per h/d band."""
    rows = [{"h/d": "all", **moments(cases[column])}]
    for lo, hi in BANDS:
        part = cases[(cases["h_over_d"] >= lo) & (cases["h_over_d"] < hi)]
        rows.append({"h/d": f"{lo:g}-{hi:g}", **moments(part[column])})
    return pd.DataFrame(rows)


def _series(rng, rate, draws, x0=10.0, x1=20.0, step=0.5, offset=0.13):
    """Volume-behind series of a Poisson flow of `rate(x)` spheres per unit travel, a point every
    `step` (20 monitor intervals in the window, off the batches' edges), as the scene records them."""
    xs = np.arange(x0 - 1.0 + offset, x1 + step + 1e-9, step)
    mid = 0.5 * (xs[1:] + xs[:-1])
    counts = np.cumsum(rng.poisson(rate(mid) * np.diff(xs), size=(draws, len(mid))), axis=1)
    return [np.column_stack([xs, xs, np.concatenate([[0.0], c])]) for c in counts]


def _rate(mean: float, shape: str, change: float):
    """Spheres per unit travel over the window 10-20 whose halves' means differ by `change` x mean:
    a step at the middle, or a linear ramp."""
    if shape == "step":
        return lambda x: mean * np.where(x < 15.0, 1.0 - change / 2, 1.0 + change / 2)
    return lambda x: mean * (1.0 + 2.0 * change * (x - 15.0) / 10.0)


def power(draws: int = 2000, c: float = 0.5, batches: int = 8, seed: int = 2029) -> pd.DataFrame:
    """Share of windows flagged (|z| > BOUND, on the change's side) by the flag's statistic for a
    flow whose halves differ by a given share of its mean, as a step at the window's middle or a
    linear ramp over it; Poisson noise with WINDOW_SPHERES / c^2 spheres in the window."""
    rng = np.random.default_rng(seed)
    mean = WINDOW_SPHERES / c ** 2 / 10.0
    rows = []
    for change in (0.0, 0.1, 0.2, 0.3, 0.5):
        row = {"halves differ by": f"{change:.0%}"}
        for shape in ("step", "ramp"):
            for sign, name in ((-1, "fall"), (1, "rise")):
                z = np.array([flow_trend_batch_z(s, 10.0, 20.0, batches)[0]
                              for s in _series(rng, _rate(mean, shape, sign * change), draws)])
                row[f"{shape} {name}"] = float(np.mean(sign * z > BOUND) if change else np.mean(np.abs(z) > BOUND))
        rows.append(row)
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="*", help="cases tables (default: the main job's published runs)")
    ap.add_argument("--batches", type=int, default=8, help="batches of mfr_sd_within (config metrics.within_batches)")
    ap.add_argument("--power", action="store_true", help="also the flag's power on synthetic flows")
    ap.add_argument("--draws", type=int, default=2000, help="synthetic windows per power cell")
    args = ap.parse_args(argv)
    tables = {p: p for p in args.cases} if args.cases else {k: str(ROOT / v) for k, v in TABLES.items()}
    fmt = {"floatfmt": ".3g", "index": False}
    for label, path in tables.items():
        cases = case_z(pd.read_csv(path), args.batches)
        print(f"## {label}: `{Path(path).relative_to(ROOT) if Path(path).is_relative_to(ROOT) else path}`, "
              f"{len(cases)} finished cases with a flow trend\n")
        print(f"max |z_plain| {cases['z_plain'].abs().max():.2f} (bound sqrt(b - 1) = {math.sqrt(args.batches - 1):.2f})\n")
        for column, title in (("z_counting", "counting-noise z (flow_trend_z, the flag before)"),
                              ("z_plain", "z on the plain batch SD, 2 mfr_sd_within / mfr"),
                              ("z_halves", f"z on the scatter about each half's mean (t, {args.batches - 2} dof, "
                                           f"as a normal score)")):
            print(f"### {title}\n")
            print(band_summary(cases, column).to_markdown(**fmt) + "\n")
        sure = cases[cases["z_flag_at_least"] > BOUND]
        print(f"Flagged for sure by the steady flag (|z| > {BOUND:g} already on the bound from the halves' scatter): "
              f"{len(sure)}" + "".join(f"\n- {r.case_id} (h/d {r.h_over_d:.2f}, trend {r.flow_trend:+.0%}, "
                                       f"z_halves {r.z_halves:+.2f})" for r in sure.itertuples()) + "\n")
        flagged = cases[cases["flagged_now"] & cases["flag_reason"].str.contains("flow fell")]
        if len(flagged):
            print("Flagged now by the counting-noise z, read on the batch noise:\n")
            print(flagged[["case_id", "h_over_d", "flow_trend", "z_counting", "z_plain", "z_halves"]].to_markdown(**fmt) + "\n")
        beyond = cases[cases["z_halves"].abs() > BOUND]
        if len(beyond):
            print(f"|z_halves| > {BOUND:g}:\n")
            print(beyond[["case_id", "h_over_d", "flow_trend", "z_counting", "z_plain", "z_halves"]].to_markdown(**fmt) + "\n")
    if args.power:
        print(f"## The flag's power: share of windows with |z| > {BOUND:g} (a steady flow: either side)\n")
        for c in (0.5, 1.0):
            print(f"Poisson noise of {WINDOW_SPHERES / c ** 2:.0f} spheres in the window (batch noise c = {c:g} at "
                  f"{WINDOW_SPHERES} spheres), {args.draws} windows a cell:\n")
            print(power(args.draws, c, args.batches).to_markdown(floatfmt=".3f", index=False) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
