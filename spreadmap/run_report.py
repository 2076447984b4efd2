"""The run summary: per set of cases, what is done, failed and flagged, with the reasons, the
regimes (spreadmap.metrics.classify: from MFR, coverage and thickness; the table's labels are
checked against the rule of the config given), and the cost."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .metrics import classify
from .table import flagged, usable


def _num(x) -> float | None:
    return None if x is None or (isinstance(x, float) and math.isnan(x)) else round(float(x), 3)


def rule_text(rules: dict) -> str:
    return (f"jamming if MFR < {rules['jam_mfr_max']:g}; else short feed if coverage < "
            f"{rules['short_feed_coverage_min']:g} or thickness / h < {rules['short_feed_thickness_min']:g}; else normal")


def stale_labels(ok: pd.DataFrame, rules: dict) -> int:
    """Finished cases whose regime label differs from the rule applied to their MFR, coverage and
    thickness (labels made by an older rule or other thresholds; a case without the layer columns
    counts as stale)."""
    if not len(ok):
        return 0
    if not {"coverage", "thickness_ratio"} <= set(ok.columns):
        return int(len(ok))
    now = classify(ok["mfr"].to_numpy(float), ok["coverage"].to_numpy(float), ok["thickness_ratio"].to_numpy(float),
                   rules)
    return int(np.sum(now != ok["regime"].fillna("").to_numpy(object)))


def set_summary(table: pd.DataFrame, rules: dict | None = None) -> dict:
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
        **({"stale_regime_labels": stale_labels(ok, rules)} if rules is not None else {}),
    }


def run_summary(tables: dict[str, pd.DataFrame], rules: dict | None = None, floor: str | None = None) -> dict:
    """The run summary: per set of cases and over the distinct cases.

    With `rules` (the config's `regime`), the rule is said and labels that differ from it are
    counted (stale_regime_labels); with `floor` (spreadmap.case.substrate.floor_label), the floor
    the cases ran on is named.

    Parameters
    ----------
    tables : dict of str to pandas.DataFrame
        Set name (e.g. a sweep) -> its results table; a case in several sets counts once in
        ``all`` (by ``case_id``).
    rules : dict or None, optional
        The config's `regime` section; None: the regime labels are not checked.
    floor : str or None, optional
        The floor the cases ran on.

    Returns
    -------
    dict
        ``sets`` (per set: ``cases``, ``done``, ``failed``, ``status_counts``, ``flagged``,
        ``usable``, ``regimes``, ``problems``, ``wall_time_s`` median/max/total [s],
        ``peak_memory_mb`` [MB] and, with `rules`, ``stale_regime_labels``), ``unique_cases``,
        ``floor`` and ``regime_rule`` (when given) and ``all`` (the same over the distinct cases).
    """
    sets = {name: set_summary(t, rules) for name, t in tables.items()}
    filled = [t for t in tables.values() if len(t)]
    unique = pd.concat(filled, ignore_index=True) if filled else pd.DataFrame()
    unique = unique.drop_duplicates("case_id") if len(unique) else unique
    return {"sets": sets, "unique_cases": int(len(unique)),
            **({"floor": floor} if floor else {}),
            **({"regime_rule": rule_text(rules)} if rules is not None else {}),
            "all": set_summary(unique, rules) if len(unique)
            else set_summary(pd.DataFrame(columns=["status", "flagged", "regime"]), rules)}


def summary_text(summary: dict) -> str:
    """The run summary as lines a user reads (the log's and the summary file's text).

    Parameters
    ----------
    summary : dict
        The result of ``run_summary``.

    Returns
    -------
    str
        One line per set and for the distinct cases, then the cases failed or flagged with their
        reasons; ends with a line break.
    """
    lines = [f"spreadmap run summary: {summary['unique_cases']} distinct cases"]
    if "floor" in summary:
        lines.append(f"  floor: {summary['floor']}")
    if "regime_rule" in summary:
        lines.append(f"  regime rule: {summary['regime_rule']}")
    for name, s in {**summary["sets"], "all (distinct)": summary["all"]}.items():
        w = s["wall_time_s"]
        lines.append(f"  {name:16s} {s['cases']:5d} cases: {s['done']} done, {s['failed']} failed, "
                     f"{s['flagged']} flagged, {s['usable']} usable; regimes {s['regimes']}; "
                     f"wall time per case median {w['median']} s, max {w['max']} s")
        if s.get("stale_regime_labels"):
            lines.append(f"  {'':16s} {s['stale_regime_labels']} finished cases carry a regime label that the rule "
                         f"does not give (older metrics: re-run their case_metrics)")
    problems = {p["case_id"]: p for s in summary["sets"].values() for p in s["problems"]}
    if problems:
        lines.append("  cases failed or flagged (kept out of training):")
        # a case that did not finish has its status as the first of its flags: not said twice
        lines += [f"    {p['case_id']}: {p['status']}: {p['reason'].removeprefix(p['status'] + ': ')}"
                  for p in problems.values()]
    return "\n".join(lines) + "\n"
