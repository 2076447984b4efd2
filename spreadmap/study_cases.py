"""The study's sweeps as planned by a configuration, and the table of the cases of a workflow
directory that have finished so far (docs/study is published from it while the study grows).

The plan is the one rules/common.smk registers: the first max(partitions) points of the seeded
scrambled-Halton sequence (`lds`), and the k^4 lattice of each k (`lattice`), at the sweep's
preset (or the config's) and the scene's packing seed; the same labels as the workflow's tables.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from spreadmap.cases import case_id
from spreadmap.sampling import halton, lattice
from spreadmap.table import build_table


def planned_sweeps(config: dict) -> dict[str, list[tuple[str, dict]]]:
    """{"lds": [(case id, label)], "lattice": [...]} for the sweeps the config has."""
    sweeps = config.get("sweeps") or {}
    ranges, seed = config.get("ranges"), config["scene"]["seed"]
    plan: dict[str, list[tuple[str, dict]]] = {}
    if "lds" in sweeps:
        preset = sweeps["lds"].get("preset") or config["preset"]
        table = halton(max(sweeps["lds"]["partitions"]), sweeps["lds"]["seed"], ranges)
        plan["lds"] = [(case_id(row, preset, seed), {"sweep": "lds", "index": int(row["index"])})
                       for row in table.to_dict("records")]
    if "lattice" in sweeps:
        preset = sweeps["lattice"].get("preset") or config["preset"]
        plan["lattice"], n = [], 0
        for k in sorted(set(sweeps["lattice"]["k"])):
            for row in lattice(k, ranges).to_dict("records"):
                plan["lattice"].append((case_id(row, preset, seed),
                                        {"sweep": "lattice", "index": n, "k": k, "index_in_lattice": int(row["index"])}))
                n += 1
    return plan


def finished_table(workdir: Path | str, planned: list[tuple[str, dict]]) -> pd.DataFrame:
    """The results table of the planned cases whose metrics exist in workdir/results/cases, in plan
    order (a case shared by two lattices appears under each of its labels, as in the workflow)."""
    cases = Path(workdir) / "results" / "cases"
    done = [(cid, label) for cid, label in planned if (cases / cid / "metrics.json").exists()]
    return build_table([cases / cid / "metrics.json" for cid, _ in done],
                       [cases / cid / "benchmark.tsv" for cid, _ in done], [label for _, label in done])


def progress(planned: dict[str, list[tuple[str, dict]]], tables: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Per sweep: cases planned, finished, usable-status counts and their CPU hours."""
    rows = []
    for name, plan in planned.items():
        table = tables[name]
        unique = table.drop_duplicates("case_id") if "case_id" in table else table  # a case shared by two lattices ran once
        status = unique["status"] if "status" in unique else pd.Series(dtype=str)
        cpu = unique["cpu_time"].sum() / 3600.0 if "cpu_time" in unique else 0.0
        rows.append({"sweep": name, "planned": len({cid for cid, _ in plan}), "finished": len(unique) if "case_id" in table else 0,
                     "ok": int((status == "ok").sum()), "failed": int((status != "ok").sum()),
                     "cpu_hours": round(float(cpu), 3)})
    return pd.DataFrame(rows)
