#!/usr/bin/env python
"""List a workflow directory's failed cases with their reasons; with --archive, move each failed
run's record and log aside (into results/cases/<case>/failed-<n>/) and print the Snakemake
command that runs those cases again, under the same case ids:

    .venv/bin/python tools/retry_failed.py [WORKDIR]                 # list (default WORKDIR: .)
    .venv/bin/python tools/retry_failed.py [WORKDIR] --archive [--case ID ...]
    snakemake sweeps --forcerun results/cases/<case>/raw.json ...    # as printed; your target

A case's id holds everything the YADE script receives, the timeout included: a retry runs the
same simulation again, worth it after a crash or a timeout the machine caused (a killed node, a
busy machine). A case that failed the script's own check fails again. Refused while a Snakemake
run holds WORKDIR (exit status 2); the logic is spreadmap/case/retry.py.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from spreadmap.case.retry import archive_run, failed_cases, rerun_command, snakemake_running


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="retry_failed.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("workdir", nargs="?", type=Path, default=Path("."), help="the workflow directory (default: .)")
    ap.add_argument("--archive", action="store_true", help="move the failed runs aside so that Snakemake runs them again")
    ap.add_argument("--case", nargs="+", metavar="ID", help="only these failed cases (default: all)")
    args = ap.parse_args(argv)
    try:
        failed = failed_cases(args.workdir)
        if args.case:
            unknown = sorted(set(args.case) - {c.case_id for c in failed})
            if unknown:
                raise ValueError(f"not failed cases of {args.workdir}: {unknown}")
            failed = [c for c in failed if c.case_id in set(args.case)]
        if args.archive and snakemake_running(args.workdir):
            raise ValueError(f"a Snakemake run holds {args.workdir} (.snakemake/locks): let it end, or "
                             "`snakemake --unlock` if none runs, then archive")
    except (FileNotFoundError, ValueError) as e:
        print(f"retry_failed.py: error: {e}", file=sys.stderr)
        return 2
    for case in failed:
        print(f"{case.case_id}: {case.reason}")
        if args.archive:
            print(f"  archived to {archive_run(case).relative_to(args.workdir)}")
    if not failed:
        print("no failed cases")
    elif args.archive:
        print(f"{len(failed)} failed case(s) archived; run them again (TARGET: the command's target, e.g. sweeps):")
        print(f"  {rerun_command(failed)}")
    else:
        print(f"{len(failed)} failed case(s) (--archive to retry them)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
