"""Snakemake entry (checkpoint): with the first n LDS cases finished, has the sweep converged
(criterion held for k consecutive batches), is the budget spent, or is another batch needed?"""
import json

import numpy as np
import pandas as pd

from spreadmap.convergence import batches_until_converged
from spreadmap.design import TARGETS
from spreadmap.table import usable
from spreadmap.logs import log_to

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
p = sm.params
n = int(sm.wildcards.n)
rows = []
for path in sm.input.metrics:
    with open(path) as fh:
        rows.append(json.load(fh))
table = pd.DataFrame(rows)
ok = usable(table)
# failed/flagged cases stay in prefix order, as NaN
values = np.where(ok[:, None], table[list(TARGETS)].to_numpy(float), np.nan)


def first(m):
    return values[:m]


result = batches_until_converged(first, batch_size=p.batch, k_consecutive=p.k_consecutive, budget=n,
                                 start=p.start, tolerance=p.tolerance, floors=p.floors, names=TARGETS)
converged = result["reason"] == "converged"
step = {"n": n, "usable": int(ok.sum()), "stop": converged or n >= p.budget,
        "reason": "converged" if converged else ("budget" if n >= p.budget else "not yet converged"),
        "converged_at": result["stopped_at"] if converged else None,
        "next_n": None if (converged or n >= p.budget) else min(n + p.batch, p.budget),
        "history": result.get("history")}
with open(sm.output.step, "w") as fh:
    json.dump(step, fh, indent=1, default=str)
print(f"converge: {n} cases, {step['reason']}" + (f", next {step['next_n']}" if step["next_n"] else ""))
