#!/usr/bin/env python
"""Resume a published study on a new machine: restore its finished cases and the main job's loop
steps into a workflow directory (a clone of the repository with the study's config.yaml), so that
Snakemake re-uses them instead of re-running them.

    .venv/bin/python tools/restore_study.py WORKDIR [--published docs/study]

Restores every case of the published cases tables (cases_*.csv, the seed repeats *_seeds.csv): its
metrics.json and benchmark.tsv from the published row, and restored.json saying so
(spreadlab/study/restore.py); a case folder with a raw YADE record is left alone. Then the loop's step
records (converge/steps/step_N.json), newer than the cases in the order they were made, and the
held-out check's files (heldout/: its points and the predictions made before its runs). The raw
records are not published: a restored case has no picture, VTK export or re-read of its overlap.
Check with `snakemake -n` in WORKDIR that only unfinished cases would run.

Each case goes back under its own case id, whose content key names the material, scene and
template it was run with: the workflow re-uses it only under a config and template that give the
same key. Tables published before content keys (issue 35) do not record that scene: they are
refused, naming the table (exit status 2), and nothing is restored.

Every file it reads is first checked against the folder's SHA256SUMS (spreadlab/study/checksums.py);
one that changed since it was published stops the restore before anything is written, with a
message naming the file and how to get it back or re-publish it (exit status 2).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from spreadlab.study.checksums import PublishedFileError, verified_bytes
from spreadlab.study.restore import UnkeyedTableError, restore_cases, restore_steps, restore_time
from spreadmap.files import atomic_path


def write_bytes_atomically(path: Path, data: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("workdir", type=Path, help="the workflow directory to restore into")
    parser.add_argument("--published", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "study",
                        help="the published study folder (default: docs/study)")
    args = parser.parse_args(argv)
    if not (args.workdir / "Snakefile").exists():
        parser.error(f"{args.workdir}: not a workflow directory (no Snakefile)")
    tables = sorted(args.published.glob("cases_*.csv")) + sorted(args.published.glob("*_seeds.csv"))
    if not tables:
        parser.error(f"{args.published}: no cases_*.csv")
    step_files = list((args.published / "converge" / "steps").glob("step_*.json"))
    # the held-out check's points and predictions (made before its runs): scoring needs them
    held = [f for f in sorted((args.published / "heldout").glob("*.csv"))
            if not (args.workdir / "heldout" / f.name).exists()]
    try:  # every published file checked before anything is restored
        held_bytes = {f: verified_bytes(f) for f in held}
        for f in tables + step_files:
            verified_bytes(f)
    except PublishedFileError as error:
        print(f"restore_study: refused: {error}", file=sys.stderr)
        return 2
    # an hour in the past, so that anything the resumed run makes is newer, but newer than the
    # workflow's code (a fresh clone dates it now, and Snakemake re-runs what is older than its script)
    base = restore_time(args.workdir)
    try:  # refused before anything is written: a table whose cases' scene is not known
        counts = restore_cases(tables, args.workdir, mtime=base)
    except UnkeyedTableError as error:
        print(f"restore_study: refused: {error}", file=sys.stderr)
        return 2
    steps = restore_steps(step_files, args.workdir, mtime=base)
    for f in held:
        write_bytes_atomically(args.workdir / "heldout" / f.name, held_bytes[f])
    if held:
        print(f"restore_study: heldout/ {', '.join(f.name for f in held)}")
    print(f"restore_study: {counts['restored']} cases restored from {len(tables)} tables "
          f"({counts['already']} restored before; {counts['kept_real']} left alone: they hold a raw record; "
          f"{counts['not_finished']} not finished: "
          f"they will run; {counts['duplicates']} listed twice), "
          f"{len(steps)} loop steps ({', '.join(steps) or 'none new'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
