"""Re-derive the numbers README.md states from the published tables under docs/ and print each
beside what README says; exits 1 when one does not round to README's or is no longer found.

    .venv/bin/python tools/readme_numbers.py [--readme README.md] [--docs docs]

The claims, their sources and the tolerance (README's rounding): spreadlab/readme_numbers.py.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from spreadlab.readme_numbers import check, report_text

ROOT = Path(__file__).resolve().parent.parent


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--readme", type=Path, default=ROOT / "README.md")
    parser.add_argument("--docs", type=Path, default=ROOT / "docs")
    args = parser.parse_args(argv)
    rows = check(args.readme.read_text(), args.docs)
    sys.stdout.write(report_text(rows))
    return 0 if all(r.status == "ok" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
