#!/usr/bin/env python3
"""Both floors' maps side by side and their ratio over the design space, with intervals (issue 36).

    .venv/bin/python tools/compare_floors.py RUN_A RUN_B [--out docs/floors/compare] [--points 1024]
                                            [--f 0.30] [--v 10] [--n 41]

RUN_A and RUN_B are working copies in which the main job ran (`snakemake --cores 2`), one per floor
(`scene.substrate.kind` in each one's config.yaml): each holds config.yaml and
results/surrogate/model.joblib. Each floor's map model gives a mean and its model SD at a point; the
ratio A / B and the difference A - B get their intervals from the two independent posteriors
(spreadlab.floors). Writes to --out:
  ratio_box.{png,pdf,csv}   the ratio at --points scrambled-Sobol' points of the box against h/d
  side_by_side.{png,pdf,csv} MFR and PD on each floor and their ratio over the (d, h) plane at f, v
  by_band.csv              the ratio per h/d band (medians, ranges, interval widths)
  summary.json             what was compared (floors, models' case counts) and the band table
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from spreadlab.floors import box_sample, by_band, compare
from spreadlab.floors_plot import plot_ratio_box, plot_side_by_side
from spreadmap.case.substrate import FLAT, ROUGH, floor_label, floor_of, mean_hollow_depth
from spreadmap.config import load
from spreadmap.design import TARGETS
from spreadmap.maps.grids import values
from spreadmap.slices import REGIME_PLANE
from spreadmap.surrogate import load_model

ROOT = Path(__file__).resolve().parent.parent



def run_of(path: Path) -> tuple[object, dict, str]:
    config = load(path / "config.yaml")
    model = load_model(path / "results" / "surrogate" / "model.joblib")
    return model, config, floor_label(config)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("run_a", type=Path)
    ap.add_argument("run_b", type=Path)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "floors" / "compare")
    ap.add_argument("--points", type=int, default=1024)
    ap.add_argument("--f", type=float, default=0.30)
    ap.add_argument("--v", type=float, default=10.0)
    ap.add_argument("--n", type=int, default=41)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)

    (model_a, config_a, label_a), (model_b, config_b, label_b) = run_of(args.run_a), run_of(args.run_b)
    kinds = (floor_of(config_a)[0], floor_of(config_b)[0])
    if kinds[0] == kinds[1]:
        print(f"both runs are on the {kinds[0]} floor: nothing to compare", file=sys.stderr)
        return 2
    names = tuple("rough floor" if k == ROUGH else "flat floor" for k in kinds)
    hollow = mean_hollow_depth(floor_of(config_a)[1]) if kinds[0] == ROUGH else None
    if kinds[0] == FLAT:
        hollow = None  # the effective-gap curve is drawn for rough over flat only
    ranges = config_a.get("ranges")

    box = compare(model_a, model_b, box_sample(args.points, args.seed, ranges), TARGETS)
    ratio_paths = plot_ratio_box(box, TARGETS, args.out / "ratio_box", names, hollow_d=hollow)

    plane = REGIME_PLANE.frame({n: values(None, args.n, n, ranges) for n in REGIME_PLANE.varying},
                               {"f": args.f, "v_mm_s": args.v}, ranges)
    grid = compare(model_a, model_b, plane, TARGETS)
    fixed = f"f = {args.f:g}, v = {args.v:g} mm/s"
    side_paths = plot_side_by_side(grid, TARGETS, args.out / "side_by_side", names, fixed)

    bands = pd.concat([by_band(box, t).assign(target=t) for t in TARGETS], ignore_index=True)
    bands.to_csv(args.out / "by_band.csv", index=False)
    summary = {
        "floor_a": label_a, "floor_b": label_b,
        "cases_a": int(len(model_a.train_X)), "cases_b": int(len(model_b.train_X)),
        "box_points": args.points, "plane": fixed,
        "ratio_defined_share": {t: float(np.mean(box[f"{t}_ratio_defined"])) for t in TARGETS},
        "ratio_box_median": {t: float(np.nanmedian(box[f"{t}_ratio"])) for t in TARGETS},
        "by_band": bands.to_dict(orient="records"),
        "figures": {k: str(v) for k, v in {**{f"ratio_box_{e}": p for e, p in ratio_paths.items()},
                                           **{f"side_by_side_{e}": p for e, p in side_paths.items()}}.items()},
    }
    (args.out / "summary.json").write_text(json.dumps(summary, indent=1, default=float) + "\n")
    with pd.option_context("display.width", 200, "display.max_columns", None):
        print(f"A: {label_a} ({summary['cases_a']} cases)\nB: {label_b} ({summary['cases_b']} cases)")
        print(bands.round(3).to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
