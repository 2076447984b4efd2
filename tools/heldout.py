#!/usr/bin/env python
"""The held-out check of a study (spreadlab.heldout_points), in two steps with the runs between:

    # 1. before any run: choose the points away from every case run, predict them, write both
    python tools/heldout.py choose --model results/surrogate/model.joblib \\
        --ran results/converge/table.csv results/tables/lds.csv --n 12 --seeds 1 2 3 4 \\
        --points heldout_points.csv --predictions heldout_predictions.csv
    # 2. run them: config `points: {csv: heldout_points.csv}`, then `snakemake points`
    # 3. score the runs against the intervals stated in step 1
    python tools/heldout.py score --points heldout_points.csv --predictions heldout_predictions.csv \\
        --table results/tables/points.csv --targets mfr pd --out heldout_score.csv
    # 4. draw one or more scored checks
    python tools/heldout.py plot --scores heldout_score.csv --labels "first check" --out heldout

Commit the predictions before the runs: they are the claim the runs test. Errors in the input
exit with status 2 and a one-line message.
"""
import argparse
import json
import sys
from pathlib import Path

import pandas as pd

from spreadlab import heldout_points
from spreadmap import config as spreadmap_config
from spreadmap.records import current_columns
from spreadmap.surrogate.cli import predict_logged, write_csv
from spreadmap.surrogate.saved_model import ModelFileError, load_model
from spreadmap.targets import current_name
from spreadmap.targets import names as target_names

ROOT = Path(__file__).resolve().parents[1]


def read_csv(path: str) -> pd.DataFrame:
    """A table, a target's columns under its name now (a published table may name it by its old one)."""
    if not Path(path).is_file():
        raise ValueError(f"file not found: {path}")
    return current_columns(pd.read_csv(path))


def choose(args) -> int:
    cfg = spreadmap_config.load(Path(args.config))
    ran = pd.concat([read_csv(p) for p in args.ran], ignore_index=True)
    points = heldout_points.choose_points(args.n, cfg["ranges"], ran, args.min_distance, args.seed, args.name_prefix)
    model = load_model(args.model)
    predictions = predict_logged(model, points, sys.stderr)
    write_csv(heldout_points.runs_of(points, args.seeds, args.preset), args.points)
    write_csv(predictions, args.predictions)
    print(f"{args.n} held-out points ({len(args.seeds)} seeds each) in {args.points}; "
          f"their predictions in {args.predictions}")
    return 0


def score(args) -> int:
    points = read_csv(args.points).drop_duplicates("name")
    runs = heldout_points.match_runs(points, read_csv(args.table))
    predictions = read_csv(args.predictions)
    tables, summaries = [], []
    for target in map(current_name, args.targets):  # an old target name: the tables read it under its new one
        table, summary = heldout_points.score(predictions, runs, target, args.level)
        tables.append(table.assign(target=target).rename(columns={target: "predicted"}))
        summaries.append(summary)
        print(f"{target}: {summary['inside']}/{summary['points']} seed means inside their "
              f"{args.level:.0%} intervals (coverage {summary['coverage']:.2f}, 95 % CI "
              f"{summary['coverage_low']:.2f}-{summary['coverage_high']:.2f}); RMSE {summary['rmse']:.4f} against "
              f"{summary['rmse_expected']:.4f} expected from the stated SDs; mean z^2 {summary['mean_z2']:.2f} "
              f"(p = {summary['p_sd_right']:.2g} for 'the SDs are too small', "
              f"{summary['p_sd_too_wide']:.2g} for 'too large')")
    if args.out:
        write_csv(pd.concat(tables, ignore_index=True), args.out)
        Path(args.out).with_suffix(".json").write_text(json.dumps(summaries, indent=1))
    return 0


def plot(args) -> int:
    from spreadmap.surrogate.plots import plot_heldout

    if len(args.labels) != len(args.scores):
        raise ValueError(f"--labels: {len(args.labels)} given for {len(args.scores)} --scores; give one per score")
    paths = plot_heldout({label: read_csv(path) for label, path in zip(args.labels, args.scores)}, args.out)
    print(f"held-out figure: {paths['png']}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="heldout.py", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="step", required=True)
    c = sub.add_parser("choose", help="choose and predict the held-out points (before any run)")
    c.add_argument("--model", required=True, help="the saved surrogate (results/surrogate/model.joblib)")
    c.add_argument("--ran", nargs="+", required=True, help="results tables of every case run (CSV)")
    c.add_argument("--n", type=int, default=12)
    c.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    c.add_argument("--preset", default="default")
    c.add_argument("--min-distance", type=float, default=0.15, help="unit-cube distance from every run")
    c.add_argument("--seed", type=int, default=2026, help="the Sobol' scrambling seed")
    c.add_argument("--name-prefix", default="heldout", help="the points' names: <prefix>_01, ...")
    c.add_argument("--config", default=str(ROOT / "config.yaml"))
    c.add_argument("--points", required=True, help="points file to write (README points format)")
    c.add_argument("--predictions", required=True, help="predictions file to write")
    s = sub.add_parser("score", help="score the runs against the predictions")
    s.add_argument("--points", required=True)
    s.add_argument("--predictions", required=True)
    s.add_argument("--table", required=True, help="results table holding the held-out runs")
    s.add_argument("--targets", nargs="+", default=list(target_names("base")))
    s.add_argument("--level", type=float, default=0.95)
    s.add_argument("--out", help="per point and target (CSV); the summary beside it (.json)")
    f = sub.add_parser("plot", help="draw scored checks: seed means against the predictions, with their intervals")
    f.add_argument("--scores", nargs="+", required=True, help="score CSVs (tools/heldout.py score --out)")
    f.add_argument("--labels", nargs="+", required=True, help="one label per score CSV")
    f.add_argument("--out", required=True, help="figure stem (writes .png, .pdf, .csv)")
    args = ap.parse_args(argv)
    try:
        return {"choose": choose, "score": score, "plot": plot}[args.step](args)
    except (ValueError, KeyError, ModelFileError) as e:  # ConfigError is a ValueError
        print(f"heldout.py: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
