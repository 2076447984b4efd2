#!/usr/bin/env python3
"""Where does the flow settle? From a run's raw records (results/cases/*/raw.json), the flow along the
blade's travel beyond the pile over each case's window mean, per h/d band, and the window opened later:
MFR and the flow-trend z of windows that open 3, 4, 5, 6 d beyond the pile and end where the case's
window ended (spreadlab.window_start; docs/steady_window).

    .venv/bin/python tools/window_start.py RESULTS_DIR [--table CASES_CSV] [--out DIR]

--table: only the cases of that table (a run's results/converge/table.csv: the loop's cases, not the
pictures' points).

Prints Markdown; with --out writes window_start.csv (one row per case and opening), flow_profile.csv
(one row per case and bin) and flow_profile.png.
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from spreadlab import window_start as ws

EDGES_D = np.arange(0.0, 11.01, 1.0)
OPENINGS_D = (3.0, 4.0, 5.0, 6.0)
PARTS = 8  # the window's own parts (metrics.within_batches' 8)
BANDS = [0, 1.5, 2, 3, 4, 9]


def read_runs(results: Path, only: set | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:
    prof, wins = [], []
    for path in sorted(results.glob("cases/*/raw.json")):
        if only is not None and path.parent.name not in only:
            continue
        raw = json.loads(path.read_text())
        if raw.get("status") != "ok" or not raw.get("behind_series"):
            continue
        p, case = raw["params"], path.parent.name
        hd = p["gap"] / p["diameter"]
        transient = (raw["window"]["x_start"] - ws.pile_end(raw)) / p["diameter"]
        for lo, hi, v in zip(EDGES_D[:-1], EDGES_D[1:], ws.flow_profile(raw, EDGES_D)):
            prof.append({"case_id": case, "h_over_d": hd, "axis": "travel_d", "from": lo, "to": hi,
                         "flow_over_window_mean": v})
        for k, v in enumerate(ws.window_profile(raw, PARTS)):
            prof.append({"case_id": case, "h_over_d": hd, "axis": "window_share", "from": k / PARTS,
                         "to": (k + 1) / PARTS, "flow_over_window_mean": v})
        base = ws.later_window(raw, transient)
        for o in OPENINGS_D:
            r = ws.later_window(raw, o)
            wins.append({"case_id": case, "h_over_d": hd, "transient_d": transient, **r,
                         "mfr_change": r["mfr_series"] / base["mfr_series"] - 1.0})
    return pd.DataFrame(prof), pd.DataFrame(wins)


def mean_se(s: pd.Series) -> str:
    s = s.dropna()
    if len(s) < 2:
        return "-"
    return f"{s.mean():+.3f} ({s.std(ddof=1) / math.sqrt(len(s)):.3f})"


def summary(wins: pd.DataFrame) -> pd.DataFrame:
    wins = wins.assign(band=pd.cut(wins["h_over_d"], BANDS))
    groups = [(o, "all", g) for o, g in wins.groupby("open_d")]
    groups += [(o, f"{b.left:g}-{b.right:g}", g) for (o, b), g in wins.groupby(["open_d", "band"], observed=True)]
    rows = []
    for o, band, g in groups:
        rows.append({"opens at d": o, "h/d": band, "cases": int(g["trend_z"].notna().sum()),
                     "window d (median)": g["length_d"].median(), "trend z mean (SE)": mean_se(g["trend_z"]),
                     "MFR / MFR of the case's own window - 1 (SE)": mean_se(g["mfr_change"])})
    return pd.DataFrame(rows)


def plot(prof: pd.DataFrame, out: Path, transient_d: float) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    prof = prof.assign(band=pd.cut(prof["h_over_d"], BANDS), mid=0.5 * (prof["from"] + prof["to"]))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), sharey=True)
    for ax, (axis, xlabel) in zip(axes, (("travel_d", "blade travel beyond the pile [d]"),
                                         ("window_share", "position in the case's own window (0: opens, 1: closes)"))):
        part = prof[prof["axis"] == axis]
        for band, g in part.groupby("band", observed=True):
            m = g.groupby("mid")["flow_over_window_mean"].agg(["mean", "std", "count"])
            ax.errorbar(m.index, m["mean"], yerr=m["std"] / np.sqrt(m["count"]), marker="o", ms=4, capsize=2,
                        label=f"h/d {band.left:g}-{band.right:g} ({g['case_id'].nunique()} cases)")
        ax.axhline(1.0, color="grey", lw=0.8)
        ax.set_xlabel(xlabel)
    axes[0].axvspan(transient_d, transient_d + 8, color="0.93", zorder=0,
                    label=f"the cases' windows: from {transient_d:.0f} d, 8 d or longer (thin gaps)")
    axes[0].set_ylabel("flow / the window's mean flow (mean, SE over cases)")
    axes[0].set_title("(a) along the travel, 1 d bins")
    axes[1].set_title(f"(b) within the window, {PARTS} equal parts")
    axes[0].legend(fontsize=7.5, loc="lower right")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="a run's results folder (holds cases/*/raw.json)")
    ap.add_argument("--table", type=Path, help="only the cases (case_id) of this cases table")
    ap.add_argument("--out", type=Path, help="write the tables and the figure here")
    args = ap.parse_args(argv)
    only = set(pd.read_csv(args.table)["case_id"]) if args.table else None
    prof, wins = read_runs(args.results, only)
    if wins.empty:
        raise SystemExit(f"no finished case with a volume-behind series under {args.results}/cases/*/raw.json")
    print(f"{wins['case_id'].nunique()} cases\n")
    print(summary(wins).to_markdown(index=False, floatfmt=".3g"))
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        wins.to_csv(args.out / "window_start.csv", index=False)
        prof.to_csv(args.out / "flow_profile.csv", index=False)
        plot(prof, args.out / "flow_profile.png", float(wins["transient_d"].median().round(2)))


if __name__ == "__main__":
    main()
