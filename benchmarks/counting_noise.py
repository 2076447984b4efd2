#!/usr/bin/env python
"""Is the seed-to-seed spread of MFR and PD counting noise, relative SD = c / sqrt(N)? Checks the
constant c of the case noise estimate (config `metrics.counting_noise_c`) against a table of
cases run with several packing seeds per cell (default: the published fidelity study,
docs/fidelity_flat/cases_presets.csv; cells = preset x point; the study's flat floor). The default
scene (rough substrate, windows sized by a precision target) is checked on the precision
benchmark's rough-substrate arms, whose cases record their own count N:

    .venv/bin/python benchmarks/counting_noise.py --cases docs/precision/cases.csv --group arm point \
        --arms physics precision precision_slow_settle window8 shipped

Per cell: seed SD of MFR and PD, N = MFR x h x W x window / sphere volume (W and the window from
the preset of the config the cases ran with, `--run-config`, default docs/fidelity_flat/config.yaml;
for PD the published box was the window), c = relative SD x
sqrt(N) with its 90 % chi-square interval; pooled c over the cells; Bartlett's test (scipy) that c
is the same in every cell (the residuals (value / cell mean - 1) x sqrt(N) have equal variances).
No raw snapshots are needed (the table's MFR gives N); N at a preset is an estimate from the mean
MFR, not each case's own count.

    .venv/bin/python benchmarks/counting_noise.py
    .venv/bin/python benchmarks/counting_noise.py --cases other_cases.csv --run-config its_config.yaml
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import pandas as pd
from scipy import stats

from spreadlab.noise_law.counting import counting_constant, pooled_constant
from spreadmap import config as spreadmap_config
from spreadmap.table import usable_cases
from spreadmap.targets import names as target_names

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=str(ROOT / "docs" / "fidelity_flat" / "cases_presets.csv"))
    ap.add_argument("--run-config", default=str(ROOT / "docs" / "fidelity_flat" / "config.yaml"),
                    help="the config the cases ran with (their presets' bed width and window)")
    ap.add_argument("--config", default=str(ROOT / "config.yaml"), help="where metrics.counting_noise_c is read")
    ap.add_argument("--group", nargs="+", default=["preset", "name"],
                    help="columns whose values make a cell of seeds (the precision benchmark's: arm point)")
    ap.add_argument("--arms", nargs="+", help="only these arms of a precision benchmark table")
    args = ap.parse_args(argv)
    config = spreadmap_config.load(args.config)
    run_config = spreadmap_config.load(args.run_config)
    cases = pd.read_csv(args.cases)
    if args.arms:
        cases = cases[cases["arm"].isin(args.arms)]
    group = tuple(args.group)
    cells = counting_constant(cases, run_config["presets"], group=group)
    pd.set_option("display.width", 200)
    show = [*group, "d_um", "h_um", "seeds", "mfr_mean", "mfr_rel_sd", "n_mfr", "c_mfr", "c_mfr_lo", "c_mfr_hi",
            "pd_mean", "pd_rel_sd", "c_pd", "c_pd_lo", "c_pd_hi"]
    print(f"cases: {args.cases} ({len(cases)} rows, {len(cells)} cells); presets of {args.run_config}")
    print(cells[show].to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    print(f"configured c (metrics.counting_noise_c): {config['metrics']['counting_noise_c']}")
    ok = usable_cases(cases)
    for name in target_names("base"):
        est, lo, hi = pooled_constant(cells, name)
        print(f"{name}: pooled c = {est:.3f}, 90 % interval [{lo:.3f}, {hi:.3f}]; cells range "
              f"{cells[f'c_{name}'].min():.3f}-{cells[f'c_{name}'].max():.3f}")
        groups = []
        for (_, row) in cells.iterrows():
            values = ok[(ok[list(group)] == row[list(group)].to_numpy()).all(axis=1)][name]
            groups.append((values / row[f"{name}_mean"] - 1.0) * math.sqrt(row[f"n_{name}"]))
        stat, p = stats.bartlett(*groups)
        print(f"{name}: Bartlett test of one c in all cells: statistic {stat:.2f} on {len(groups) - 1} dof, p = {p:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
