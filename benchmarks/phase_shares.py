#!/usr/bin/env python
"""The share of a case's steps in each phase: settle, relax, the blade's approach to the window,
and the window itself, from finished cases' raw results (their `phase_cost` record and the
window's opening snapshot). Cases are grouped by the name of their directory's parent's prefix
given with --group (default: the directory name up to the last '-s<seed>').

    .venv/bin/python benchmarks/phase_shares.py /work/runs/cost_ab/cases/shipped-*/raw.json
"""
from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import numpy as np

from spreadmap.case.identity import repeat_group

PHASES = ("settle", "relax", "approach", "window")


def phase_steps(raw: dict) -> dict:
    """Steps per phase; the move phase split where the window opened."""
    cost = raw["phase_cost"]
    move_start = cost["settle"]["steps"] + cost["relax"]["steps"]
    window_iter = raw["snapshots"]["window_start"]["iter"]
    return {"settle": cost["settle"]["steps"], "relax": cost["relax"]["steps"],
            "approach": window_iter - move_start, "window": move_start + cost["move"]["steps"] - window_iter}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("raw", nargs="+", help="raw.json files of finished cases")
    args = ap.parse_args(argv)
    groups: dict = {}
    for path in map(Path, args.raw):
        raw = json.loads(path.read_text())
        if raw.get("status") != "ok" or "phase_cost" not in raw:
            continue
        params = raw.get("params") or {}
        name = (repeat_group(params) if {"point", "preset", "seed"} <= set(params)  # seed repeats of one content
                else re.sub(r"-s\d+(-[0-9a-f]{8})?$", "", path.parent.name))
        groups.setdefault(name, []).append(phase_steps(raw))
    print(f"{'cases':40} {'n':>2} {'steps':>8}  " + " ".join(f"{p:>9}" for p in PHASES))
    for name, rows in sorted(groups.items()):
        total = np.array([sum(r.values()) for r in rows], float)
        shares = {p: np.mean([r[p] for r in rows] / total) for p in PHASES}
        print(f"{name:40} {len(rows):2d} {total.mean():8.0f}  " + " ".join(f"{100 * shares[p]:8.1f}%" for p in PHASES))
    return 0


if __name__ == "__main__":
    sys.exit(main())
