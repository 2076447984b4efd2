#!/usr/bin/env python
"""Re-read the peak overlap's cause of finished cases with the scene's current attribution rule.

    .venv/bin/python tools/reattribute_wedges.py WORKFLOW_DIR [--cases ID ...] [--dry-run]

The scene splits each new peak overlap into `peak_overlap_wedged` (spheres the moving blade
presses) and `peak_overlap_free` (the stability flag's business). When that rule changes (on
2026-12-02 it grew from the spheres touching the blade to those within two contacts of it), the
cases that ran under the old rule keep its reading. This tool re-runs each case (by default:
every finished case flagged for a free peak overlap and nothing else) from its own parameters
with the current scene script, in a temporary directory, and requires the same simulation: the
same status, number of steps and sphere positions at the end of the measurement window, bit for
bit. Only then does it replace the two attribution fields of the case's raw.json and of the
launcher's copy simulated.json (recording the old values under `reattributed`), and rewrite its
metrics.json; all keep their modification times, so Snakemake's mtime trigger does not re-run
the steps and tables that read them (a workflow run after this reads the new flags; those before
keep what they decided). A case whose re-run differs is left as it was and reported. The
parameters come from the raw record, which carries those the case ran with (`params`).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

from spreadmap import config as cfgmod
from spreadmap.case.launcher import run_case, write_json_atomically
from spreadmap.case.migrate import ADDED_SINCE_BYTES
from spreadmap.case.render import render, template_sha256
from spreadmap.metrics import case_metrics

FIELDS = ("peak_overlap_free", "peak_overlap_wedged")


def overlap_flagged_only(metrics: dict) -> bool:
    reasons = [r for r in str(metrics.get("flag_reason") or "").split("; ") if r]
    return bool(reasons) and all(r.startswith("peak overlap ") for r in reasons)


def same_simulation(old: dict, new: dict) -> str:
    """'' when the two raw records are the same simulation, else what differs."""
    for key in ("status", "steps"):
        if old.get(key) != new.get(key):
            return f"{key} {old.get(key)} vs {new.get(key)}"
    a = (old.get("snapshots") or {}).get("window_end", {}).get("positions")
    b = (new.get("snapshots") or {}).get("window_end", {}).get("positions")
    if a is None or a != b:
        return "sphere positions at the window's end differ"
    return ""


def reattribute(case_dir: Path, config: dict, dry_run: bool = False) -> dict:
    raw_path, metrics_path = case_dir / "raw.json", case_dir / "metrics.json"
    old = json.loads(raw_path.read_text())
    # (a record from before the scene's later parameters: at the values that simulate what it ran)
    params = {**ADDED_SINCE_BYTES, **old["params"], "scene_sha256": template_sha256()}
    with tempfile.TemporaryDirectory(prefix="reattribute-") as tmp:
        script = Path(tmp) / "case.py"
        script.write_text(render(params))
        result = run_case(script, Path(tmp) / "raw.json", Path(tmp) / "run.log", params["timeout_s"])
        if result["outcome"] != "ok":
            return {"case": case_dir.name, "done": False, "why": f"re-run {result['outcome']}: {result['reason']}"}
        new = json.loads((Path(tmp) / "raw.json").read_text())
    differs = same_simulation(old, new)
    row = {"case": case_dir.name, **{f"old_{k}": old.get(k) for k in FIELDS}, **{f"new_{k}": new.get(k) for k in FIELDS},
           "rerun_cpu_s": round(result["cpu_time"], 1)}
    if differs:
        return {**row, "done": False, "why": f"not the same simulation: {differs}"}
    if dry_run:
        return {**row, "done": False, "why": "dry run"}
    simulated_path = case_dir / "simulated.json"  # the launcher's re-use copy (spreadmap.case.launcher.simulate)
    times = {p: (p.stat().st_atime, p.stat().st_mtime) for p in (raw_path, metrics_path, simulated_path) if p.exists()}
    note = {"reattributed": {"tool": "tools/reattribute_wedges.py", "scene_sha256": params["scene_sha256"],
                             **{f"old_{k}": old.get(k) for k in FIELDS}}}
    updated = {**old, **{k: new[k] for k in FIELDS}, **note}
    write_json_atomically(raw_path, updated)
    if simulated_path.exists():
        simulated = json.loads(simulated_path.read_text())
        if not same_simulation(old, simulated):
            write_json_atomically(simulated_path, {**simulated, **{k: new[k] for k in FIELDS}, **note})
    metrics = case_metrics(updated, config["regime"], config["stability"], config["metrics"])
    write_json_atomically(metrics_path, metrics)
    for path, (atime, mtime) in times.items():
        os.utime(path, (atime, mtime))
    return {**row, "done": True, "flagged_now": metrics["flagged"], "why": metrics["flag_reason"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("workdir", type=Path)
    ap.add_argument("--cases", nargs="*", help="case ids (default: every case flagged for its peak overlap only)")
    ap.add_argument("--dry-run", action="store_true", help="re-run and compare, change nothing")
    args = ap.parse_args(argv)
    config = cfgmod.load(args.workdir / "config.yaml")
    cases = args.workdir / "results" / "cases"
    if args.cases:
        chosen = [cases / c for c in args.cases]
    else:
        chosen = [p.parent for p in sorted(cases.glob("*/metrics.json"))
                  if overlap_flagged_only(json.loads(p.read_text()))]
    print(f"{len(chosen)} cases to re-read", flush=True)
    rows = []
    for case_dir in chosen:
        row = reattribute(case_dir, config, args.dry_run)
        rows.append(row)
        print(json.dumps(row), flush=True)
    return 0 if all(r["done"] or r["why"] == "dry run" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
