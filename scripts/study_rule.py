"""Snakemake entry: convergence of the sweeps' statistics, summary JSON and figures."""
import json
from pathlib import Path

import pandas as pd

from spreadmap import study_rule as cv
from spreadmap.design import TARGETS
from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.records import read_table
from spreadmap.study_rule import rule_plots
from spreadmap.table import usable

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
p = sm.params
tables = {Path(t).stem: read_table(t) for t in sm.input.tables}
out = Path(sm.output.summary).parent
frames, verdicts, long = [], {}, []
for name, table in tables.items():
    partition_col = "k" if name == "lattice" else None
    partitions = None if partition_col else sorted(p.partitions)
    conv = cv.convergence_table(table, TARGETS, partitions=partitions, tolerance=p.tolerance, floors=p.floors,
                                partition_col=partition_col)
    frames.append(conv.assign(sweep=name))
    verdicts[name] = conv
    long.append(rule_plots.partition_values(table, name, TARGETS, partitions=partitions, partition_col=partition_col))
write_text_atomically(sm.output.partitions, pd.concat(frames, ignore_index=True).to_csv(index=False))

lds = tables["lds"][usable(tables["lds"])].sort_values("index")
running = cv.running_statistics(lds[list(TARGETS)].to_numpy(), start=2, names=TARGETS)
write_text_atomically(sm.output.running, running.to_csv(index=False))
stable = cv.first_stable_n(running, tolerance=p.tolerance, window=p.window, floors=p.floors)
summary = cv.summary(verdicts, tolerance=p.tolerance)
summary["lds_case_by_case"] = stable
summary["note"] = ("partitions: converged at the first N where all five statistics of MFR and PD change by less "
                   "than the tolerance from the previous partition; case by case: see lds_case_by_case")
write_text_atomically(sm.output.summary, json.dumps(summary, indent=1, default=str))
rule_plots.plot_distributions(pd.concat(long, ignore_index=True), out / "distributions", TARGETS, floor=p.floor)
sweeps_stats = {name: conv for name, conv in verdicts.items()}
sweeps_stats["lds case by case"] = running
rule_plots.plot_statistics(sweeps_stats, out / "statistics", TARGETS, tolerance=p.tolerance, floors=p.floors,
                      floor=p.floor)
print(json.dumps(summary, indent=1, default=str))
