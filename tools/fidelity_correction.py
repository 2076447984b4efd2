#!/usr/bin/env python3
"""The factor from the main job's preset to `reference`, from a fidelity study's paired cases (issue 32).

    .venv/bin/python tools/fidelity_correction.py TABLE [--config config.yaml] [--out docs/fidelity/correction]
                                                  [--preset default] [--reference reference]

TABLE is a fidelity study's results table (`snakemake fidelity` writes results/tables/fidelity.csv):
the same points and packing seeds at both presets. Writes to --out: correction.json (per target the
factor, its SD at a point not run, the random-effects evidence, the points), pairs.csv, and the figure
correction.{png,pdf,csv}; prints the `fidelity_correction` config block (spreadlab.paired_factor).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd
import yaml

from spreadlab.paired_factor import config_block, correction, pairs
from spreadmap.case.substrate import floor_label, floor_of
from spreadmap.config import load
from spreadmap.fidelity.fidelity_plots import correction_figure

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("table", type=Path)
    ap.add_argument("--config", type=Path, default=ROOT / "config.yaml", help="the config the study ran (its floor)")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "fidelity" / "correction")
    ap.add_argument("--preset", default="default")
    ap.add_argument("--reference", default="reference")
    ap.add_argument("--source", default=None, help="what the config block names as its source (default: --out)")
    args = ap.parse_args(argv)

    table = pd.read_csv(args.table)
    result = correction(table, args.preset, args.reference)
    if result["points"] < 2:
        print(f"{args.table}: {result['pairs']} usable pairs at {result['points']} points; at least two points are needed",
              file=sys.stderr)
        return 2
    p = pairs(table, args.preset, args.reference)
    args.out.mkdir(parents=True, exist_ok=True)
    p.to_csv(args.out / "pairs.csv", index=False)
    study_config = load(args.config)
    floor = floor_label(study_config)
    correction_figure(result, p, args.out / "correction", floor)
    source = args.source or str(args.out.relative_to(ROOT) if args.out.is_relative_to(ROOT) else args.out)
    block = config_block(result, source, floor_of(study_config)[0])
    (args.out / "correction.json").write_text(json.dumps({**result, "floor": floor, "config_block": block},
                                                         indent=1, default=float) + "\n")
    print(yaml.safe_dump({"fidelity_correction": block}, sort_keys=False))
    for t, r in result["targets"].items():
        re = r["random_effects"]
        print(f"{t}: factor {r['factor']:.4f}, mean's 95 % {r['mean_95'][0]:.4f}-{r['mean_95'][1]:.4f}, at a point not run "
              f"{r['new_point_95'][0]:.4f}-{r['new_point_95'][1]:.4f} (SD {r['sd']:.4f}); points differ: Q {re['q']:.2f} "
              f"on {re['dof']} dof, p {re['q_p']:.3f}, tau {re['tau']:.4f}; slope on ln(h/d) {r['slope_ln_hd']:+.4f} "
              f"(SE {r['slope_se']:.4f}); CPU reference / preset {result['cpu_ratio']:.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
