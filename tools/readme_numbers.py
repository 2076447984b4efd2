"""Re-derive the numbers README.md (and the guide's pages, where they state what is current) state
from the published tables under docs/ and print each beside what the page says; exits 1 when one
does not round to the page's or is no longer found.

    .venv/bin/python tools/readme_numbers.py [--root .] [--docs docs]

The claims, their pages, their sources and the tolerance (the page's rounding):
spreadlab/readme_numbers.py.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from spreadlab.readme_numbers import check_pages, report_text

ROOT = Path(__file__).resolve().parent.parent


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=ROOT, help="the repository: README.md and docs/guide/")
    parser.add_argument("--docs", type=Path, default=None, help="the published tables (default ROOT/docs)")
    args = parser.parse_args(argv)
    rows = check_pages(args.root, args.docs)
    sys.stdout.write(report_text(rows))
    return 0 if all(r.status == "ok" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
