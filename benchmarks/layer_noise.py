#!/usr/bin/env python
"""Do the layer measures' stated noise SDs (the block jackknife of spreadmap.metrics.layer,
`<measure>_sd`) match the spread over packing seeds? Measures raw YADE records of design points
run with several packing seeds (the case directory's name less its `-s<seed>` ending is the
point), with the shipped metrics code and the config's `metrics` settings, and prints per measure
the pooled SD over seeds (with its 90 % chi-square interval) against the root mean square of the
stated SDs, for MFR and PD (counting law) as well as the layer.

    .venv/bin/python benchmarks/layer_noise.py /work/runs/precision/cases/shipped-*/raw.json
    .venv/bin/python benchmarks/layer_noise.py --block-d 1 --csv out.csv a-s1/raw.json a-s2/raw.json ...
"""
from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from spreadmap import config as spreadmap_config
from spreadmap.case.identity import repeat_group
from spreadmap.metrics import measure

ROOT = Path(__file__).resolve().parent.parent

MEASURES = ("mfr", "pd", "layer_fill", "coverage", "roughness_d", "thickness_ratio")


def point_of(path: Path, raw: dict) -> str:
    """The design point of a case: what its seed repeats share (spreadmap.case.identity.repeat_group, from the
    raw record's parameters), else its directory's name without the packing seed's `-s<n>` (and key)."""
    if isinstance(raw.get("params"), dict) and {"point", "preset", "seed"} <= set(raw["params"]):
        return repeat_group(raw["params"])
    return re.sub(r"-s\d+(-[0-9a-f]{8})?$", "", path.parent.name)


def pooled(table: pd.DataFrame, column: str, level: float = 0.9) -> tuple[float, float, float, int]:
    """Pooled SD over seeds within points, its chi-square interval and its degrees of freedom."""
    groups = table.groupby("point")[column]
    dof = int((groups.count() - 1).clip(lower=0).sum())
    ss = float((groups.var(ddof=1).fillna(0.0) * (groups.count() - 1)).sum())
    sd = math.sqrt(ss / dof)
    a = (1 - level) / 2
    return sd, math.sqrt(ss / stats.chi2.ppf(1 - a, dof)), math.sqrt(ss / stats.chi2.ppf(a, dof)), dof


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("raw", nargs="+", help="raw.json files of finished cases, several seeds per point")
    ap.add_argument("--config", default=str(ROOT / "config.yaml"), help="config whose `metrics` settings are used")
    ap.add_argument("--block-d", type=float, help="block length in d (default: the config's metrics.layer_block_d)")
    ap.add_argument("--csv", help="write the per-measure summary here")
    args = ap.parse_args(argv)
    settings = dict(spreadmap_config.load(Path(args.config))["metrics"])
    if args.block_d is not None:
        settings["layer_block_d"] = args.block_d
    rows = []
    for name in args.raw:
        path = Path(name)
        raw = json.loads(path.read_text())
        if raw.get("status") != "ok":
            continue
        rows.append({"point": point_of(path, raw), **measure(raw, settings)})
    table = pd.DataFrame(rows)
    out = []
    for m in MEASURES:
        sd, low, high, dof = pooled(table, m)
        stated = float(np.sqrt(np.mean(table[f"{m}_sd"] ** 2)))
        ratio = lambda sd, stated=stated: stated / sd if sd > 0 else math.nan  # noqa: E731 (no spread over seeds: no ratio)
        out.append({"measure": m, "seed_sd": sd, "seed_sd_low": low, "seed_sd_high": high, "dof": dof,
                    "stated_sd": stated, "ratio": ratio(sd), "ratio_low": ratio(high), "ratio_high": ratio(low)})
    summary = pd.DataFrame(out)
    print(f"{len(table)} cases at {table['point'].nunique()} points; layer blocks of {settings.get('layer_block_d')} d")
    print(summary.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    if args.csv:
        summary.to_csv(args.csv, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
