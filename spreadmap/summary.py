"""The run summary: per set of cases, what is done, failed and flagged, with the reasons, the
regimes, and the cost."""
from __future__ import annotations

import math

import pandas as pd

from .table import flagged, usable


def _num(x) -> float | None:
    return None if x is None or (isinstance(x, float) and math.isnan(x)) else round(float(x), 3)


def set_summary(table: pd.DataFrame) -> dict:
    status = table["status"].value_counts().to_dict() if len(table) else {}
    ok = table[table["status"] == "ok"] if len(table) else table
    is_flagged = flagged(table)
    problems = table[(table["status"] != "ok").to_numpy() | is_flagged] if len(table) else table
    wall = table["wall_time"].dropna() if "wall_time" in table else pd.Series(dtype=float)
    return {
        "cases": int(len(table)),
        "done": int(status.get("ok", 0)),
        "failed": int(len(table) - status.get("ok", 0)),
        "status_counts": {k: int(v) for k, v in status.items()},
        "flagged": int(is_flagged.sum()),
        "usable": int(usable(table).sum()),
        "regimes": {k: int(v) for k, v in ok["regime"].value_counts().items()} if len(ok) else {},
        "problems": [{"case_id": r.case_id, "status": r.status, "reason": r.flag_reason}
                     for r in problems.itertuples()],
        "wall_time_s": {"median": _num(wall.median()) if len(wall) else None,
                        "max": _num(wall.max()) if len(wall) else None,
                        "total": _num(wall.sum()) if len(wall) else None},
        "peak_memory_mb": _num(table["max_rss_mb"].max()) if "max_rss_mb" in table and len(table) else None,
    }


def run_summary(tables: dict[str, pd.DataFrame]) -> dict:
    sets = {name: set_summary(t) for name, t in tables.items()}
    filled = [t for t in tables.values() if len(t)]
    unique = pd.concat(filled, ignore_index=True) if filled else pd.DataFrame()
    unique = unique.drop_duplicates("case_id") if len(unique) else unique
    return {"sets": sets, "unique_cases": int(len(unique)),
            "all": set_summary(unique) if len(unique) else set_summary(pd.DataFrame(columns=["status", "flagged"]))}


def summary_text(summary: dict) -> str:
    lines = [f"spreadmap run summary: {summary['unique_cases']} distinct cases"]
    for name, s in {**summary["sets"], "all (distinct)": summary["all"]}.items():
        w = s["wall_time_s"]
        lines.append(f"  {name:16s} {s['cases']:5d} cases: {s['done']} done, {s['failed']} failed, "
                     f"{s['flagged']} flagged, {s['usable']} usable; regimes {s['regimes']}; "
                     f"wall time per case median {w['median']} s, max {w['max']} s")
    problems = {p["case_id"]: p for s in summary["sets"].values() for p in s["problems"]}
    if problems:
        lines.append("  cases failed or flagged (kept out of training):")
        # a case that did not finish has its status as the first of its flags: not said twice
        lines += [f"    {p['case_id']}: {p['status']}: {p['reason'].removeprefix(p['status'] + ': ')}"
                  for p in problems.values()]
    return "\n".join(lines) + "\n"
