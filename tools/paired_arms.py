#!/usr/bin/env python
"""An arm against a base arm, case by case (same point, same packing seed): the pre-registered
numbers of a scene change's A/B (docs/steady_window, docs/heap_size).

    .venv/bin/python tools/paired_arms.py docs/steady_window/transient_fed/cases.csv --base shipped \\
        --arms fed_transient window5_fed_transient --out docs/steady_window/transient_fed/paired.md

Reads a cases table with the columns benchmarks/precision.py writes (arm, point, seed, status,
flagged, mfr, pd, mfr_sd, pd_sd, cpu_time, heap_end_h2). A pair is a point and seed both arms ran
to the end ("ok"). Per arm (the numbers: spreadlab.experiments.paired):

- **CPU**: the geometric mean of the pairs' CPU ratios arm / base, with a 95 % t interval on the
  log ratios (the pairs independent);
- **MFR and PD**: the pooled mean relative difference (arm - base) / base over the pairs, with a
  90 % t interval; per point the mean difference over its seeds and its z against the SE from the
  cases' recorded SDs (``mfr_sd``, ``pd_sd``: each case's own noise estimate, independent of the
  difference);
- **flags**: pairs where the arm's case is flagged and the base's is not; the least heap at the
  window's end (``heap_end_h2``, h^2).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from spreadlab.experiments.paired import by_point, cpu_ratio, flagged, pairs, relative_shift
from spreadmap.design import TARGETS  # mfr, pd (spreadmap.targets)
from spreadmap.files import write_text_atomically


def report(cases: pd.DataFrame, arm: str, base: str) -> str:
    """The markdown section of one arm against the base."""
    p = pairs(cases, arm, base)
    lines = [f"## {arm} against {base}", ""]
    if p.empty:
        return "\n".join(lines + ["No pair finished.", ""])
    ran = cases[cases["arm"] == arm]
    g, lo, hi = cpu_ratio(p)
    ratios = p["cpu_time_arm"] / p["cpu_time_base"]
    lines += [f"- **Pairs**: {len(p)} (point, seed) of {len(ran)} {arm} cases at {p['point'].nunique()} points.",
              f"- **CPU per case, arm / base**: geometric mean {g:.3f} (95 % CI {lo:.3f}-{hi:.3f}); "
              f"the pairs' ratios {ratios.min():.2f}-{ratios.max():.2f}."]
    tables = {t: by_point(p, t) for t in TARGETS}
    for t in TARGETS:
        m, mlo, mhi = relative_shift(p, t)
        pts = tables[t]
        worst = pts.loc[pts["z"].abs().idxmax()] if pts["z"].notna().any() else None
        text = (f"; the largest point z {worst['z']:+.2f} ({worst['point']})" if worst is not None else "")
        lines.append(f"- **{t.upper()}, (arm - base) / base pooled**: {100 * m:+.2f} % (90 % CI {100 * mlo:+.2f} "
                     f"to {100 * mhi:+.2f} %){text}.")
    new_flags = flagged(p["flagged_arm"]) & ~flagged(p["flagged_base"])
    heap = pd.to_numeric(p["heap_end_h2_arm"], errors="coerce") if "heap_end_h2_arm" in p else pd.Series(dtype=float)
    lines.append(f"- **Flags**: {int(new_flags.sum())} pairs flagged in the arm and not in the base"
                 + (f" ({', '.join(f'{r.point} s{r.seed}' for r in p[new_flags].itertuples())})" if new_flags.any() else "")
                 + (f"; heap at the window's end at least {heap.min():.2f} h^2 in the arm's paired cases"
                    if heap.notna().any() else "") + ".")
    lines += ["", "| point | seeds | " + " | ".join(f"{t.upper()} diff (SE) | z" for t in TARGETS)
              + " | CPU arm / base |", "|---|---|" + "---|---|" * len(TARGETS) + "---|"]
    tables = {t: table.set_index("point") for t, table in tables.items()}
    for point, g_pt in p.groupby("point", sort=True):
        cells = [f"{tables[t].loc[point, 'diff']:+.4f} ({tables[t].loc[point, 'se']:.4f}) | "
                 f"{tables[t].loc[point, 'z']:+.2f}" for t in TARGETS]
        ratio = g_pt["cpu_time_arm"].sum() / g_pt["cpu_time_base"].sum()
        lines.append(f"| {point} | {len(g_pt)} | " + " | ".join(cells) + f" | {ratio:.2f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv", type=Path, help="the cases table (benchmarks/precision.py --csv)")
    ap.add_argument("--base", default="shipped", help="the arm the others are paired with")
    ap.add_argument("--arms", nargs="+", help="the arms to compare (default: every other arm in the table)")
    ap.add_argument("--out", type=Path, help="write the markdown here")
    args = ap.parse_args(argv)
    cases = pd.read_csv(args.csv)
    missing = [c for c in ("arm", "point", "seed", "status", "flagged", "cpu_time", *TARGETS,
                           *(f"{t}_sd" for t in TARGETS)) if c not in cases]
    if missing:
        ap.error(f"{args.csv} lacks the columns {missing}")
    if args.base not in set(cases["arm"]):
        ap.error(f"--base {args.base!r} is not an arm of {args.csv} (arms: {sorted(set(cases['arm']))})")
    arms = args.arms or [a for a in dict.fromkeys(cases["arm"]) if a != args.base]
    text = "\n".join(report(cases, a, args.base) for a in arms)
    print(text)
    if args.out:
        write_text_atomically(args.out, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
