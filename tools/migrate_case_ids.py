#!/usr/bin/env python
"""Rename a workflow directory's case folders named before content keys (issue 35) to their content
ids, then carry the cases keyed by the scene template's bytes (issue 35 to issue 65) of a template
whose code today's simulates identically (spreadmap.case.migrate.BYTE_HASHED_TEMPLATES: among them
the dry cases of the template before adhesion, issue 49) to today's ids, keyed by what they simulate,
without re-running them (spreadmap/case/migrate.py):

    .venv/bin/python tools/migrate_case_ids.py WORKDIR [--dry-run]

A folder whose parameters are recorded in it (raw.json, simulated.json or case.py) gets its content
id; the others (e.g. cases restored from a published table before content keys) are left where they
are and listed, never deleted. Run it once, with no snakemake running in WORKDIR; run it again at any
time: it only touches folders still named the old way. Afterwards `snakemake -n` in WORKDIR lists
only the cases whose content (material, scene, template) differs from the migrated ones.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from spreadmap import config as spreadmap_config
from spreadmap.case.migrate import carry_to_code_keys, migrate_case_folders


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("workdir", type=Path, help="the workflow directory (its results/cases/ is migrated)")
    parser.add_argument("--dry-run", action="store_true", help="say what would be renamed, rename nothing")
    parser.add_argument("--configfile", type=Path, default=None,
                        help="the config the cases are carried to (default: WORKDIR/config.yaml)")
    args = parser.parse_args(argv)
    cases = args.workdir / "results" / "cases"
    if not cases.is_dir():
        parser.error(f"{cases}: no such folder")
    report = migrate_case_folders(cases, dry_run=args.dry_run)
    verb = "would rename" if args.dry_run else "renamed"
    for old, new, source in report["renamed"]:
        print(f"migrate_case_ids: {verb} {old} -> {new} (parameters from {source})")
    for old, why in report["left"]:
        print(f"migrate_case_ids: left {old}: {why}")
    print(f"migrate_case_ids: {len(report['renamed'])} case folders {verb}, {len(report['left'])} left as they are")
    config = spreadmap_config.load(args.configfile or args.workdir / "config.yaml")
    carried = carry_to_code_keys(cases, config, dry_run=args.dry_run)
    for old, new in carried["renamed"]:
        print(f"migrate_case_ids: {verb} {old} -> {new} (keyed by the template's bytes; today's code simulates the same)")
    for old, why in carried["left"]:
        print(f"migrate_case_ids: left {old}: {why}")
    print(f"migrate_case_ids: {len(carried['renamed'])} case folders keyed by a template's bytes {verb}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
