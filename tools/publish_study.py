#!/usr/bin/env python
"""Publish the study (issue 17) from a workflow directory into docs/study/, as far as it has run.

    .venv/bin/python tools/publish_study.py WORKFLOW_DIR [--out docs/study]

Writes the cases tables of the sweeps its config plans (cases_lds.csv, cases_lattice.csv: every
finished case, in plan order, with the workflow's labels), progress.csv (per sweep: planned,
finished, failed, CPU hours, and the CPU hours still to go, predicted by a cost model of the
finished cases), the config it ran with, and copies the analyses that exist (the
sweeps' convergence, the converge run's steps so far (and, while it runs, the table of its cases
so far), its table and stopping path, the surrogate, the maps, the
held-out points' table); what does not exist yet is listed. Then summary.md (and the trends'
tables trend_*.csv) from what is there (spreadlab.study.summary). Last, the folder's SHA256SUMS
(spreadlab.study.checksums: what tools/restore_study.py verifies before it restores). A later session
grows the same workflow directory (Snakemake re-uses every finished case) and publishes again.
"""
from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

from spreadlab.study.cases import cpu_hours_to_go, finished_table, loop_cases, planned_sweeps, progress
from spreadlab.study.checksums import write_manifest
from spreadlab.study.summary import summary_markdown, trends
from spreadmap import config as cfgmod
from spreadmap.case.identity import readable_part
from spreadmap.case.render import template_sha256
from spreadmap.files import write_text_atomically
from spreadmap.table import write_table

ROOT = Path(__file__).resolve().parents[1]

COPIES = {  # source under the workflow directory -> destination under --out
    "results/convergence": "convergence",
    "results/converge/summary.txt": "converge/summary.txt",
    "results/converge/stopped.json": "converge/stopped.json",
    "results/converge/path.png": "converge/path.png",
    "results/converge/table.csv": "cases_converge.csv",
    "results/surrogate": "surrogate",
    "results/maps": "maps",
    "results/tables/points.csv": "cases_heldout.csv",
    "heldout": "heldout",  # tools/heldout.py's points, predictions (made before the runs) and score
}


def unmatched_cases(workdir: Path, plan: dict) -> list[str]:
    """Finished case folders of workdir at a planned design point whose id is none of the plan's."""
    ids = {cid for cases in plan.values() for cid, _ in cases}
    points = {readable_part(cid) for cid in ids}
    folders = sorted(p.parent.name for p in (workdir / "results" / "cases").glob("*/metrics.json"))
    return [name for name in folders if name not in ids and readable_part(name) in points]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("workdir", type=Path)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "study")
    args = ap.parse_args(argv)
    config = cfgmod.load(args.workdir / "config.yaml")
    # the case ids the workflow directory's own scene template gives (content ids, spreadmap.case.identity)
    template = args.workdir / "yade_scripts" / "spreading_case.py"
    sha = template_sha256(template) if template.exists() else None
    args.out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(args.workdir / "config.yaml", args.out / "config.yaml")
    plan = planned_sweeps(config, scene_sha256=sha)
    tables = {name: finished_table(args.workdir, cases) for name, cases in plan.items()}
    unmatched = unmatched_cases(args.workdir, plan)
    if unmatched:
        print(f"publish_study: {len(unmatched)} case folders of {args.workdir} are at planned design points but under "
              f"other content ids (another material, scene or spreadmap version than this config and "
              f"{'its' if sha else 'the shipped'} template give), e.g. {unmatched[0]}; they are not published",
              file=sys.stderr)
    for name, table in tables.items():
        write_table(table, args.out / f"cases_{name}.csv")
    done = progress(plan, tables, cpu_hours_to_go(config, tables, scene_sha256=sha))
    write_table(done, args.out / "progress.csv")
    print(done.to_string(index=False))
    missing = []
    for source, target in COPIES.items():
        src, dst = args.workdir / source, args.out / target
        if not src.exists():
            missing.append(source)
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        if src.is_dir():
            shutil.copytree(src, dst, dirs_exist_ok=True)
        else:
            shutil.copyfile(src, dst)
    steps = sorted((args.workdir / "results" / "converge").glob("step_*.json"))
    if steps:  # the loop's path so far, batch by batch (a loop still running has no stopped.json)
        (args.out / "converge" / "steps").mkdir(parents=True, exist_ok=True)
        for step in steps:
            shutil.copyfile(step, args.out / "converge" / "steps" / step.name)
        if not (args.workdir / "results" / "converge" / "table.csv").exists():  # its cases so far
            records = [json.loads(s.read_text()) for s in steps]
            write_table(finished_table(args.workdir, loop_cases(config, records, scene_sha256=sha)),
                        args.out / "cases_converge.csv")
    if missing:
        print("not yet run:", ", ".join(missing))
    effects = trends(args.out, config.get("ranges"))
    for variable, effect in effects.items():
        write_text_atomically(args.out / f"trend_{variable}.csv", effect.to_csv(index=False))
    text = summary_markdown(args.out, effects)
    write_text_atomically(args.out / "summary.md", text)
    print(text)
    print(f"checksums: {write_manifest(args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
