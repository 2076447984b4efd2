#!/usr/bin/env python
"""Re-make (or check) the SHA256SUMS manifests of the published folders (spreadlab/study/checksums.py).

    .venv/bin/python tools/publish_checksums.py [FOLDER ...]          # re-make: after publishing
    .venv/bin/python tools/publish_checksums.py --check [FOLDER ...]  # check: exit 1 on a mismatch

Without FOLDER: every published folder of this repository (docs/study, docs/precision,
docs/fidelity, docs/fidelity_flat, docs/main_job). The restore (tools/restore_study.py) refuses a
table whose bytes differ from its folder's manifest; run this after writing a published table on
purpose (tools/publish_study.py and tools/publish_fidelity.sh run it themselves). Each manifest is
in coreutils' format: `cd docs/study && sha256sum -c SHA256SUMS` checks it too.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from spreadlab.study.checksums import MANIFEST, PUBLISHED, check_folder, listed_files, write_manifest

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folders", nargs="*", type=Path, help="published folders (default: this repository's)")
    ap.add_argument("--check", action="store_true", help="check the manifests instead of re-making them")
    args = ap.parse_args(argv)
    folders = args.folders or [ROOT / name for name in PUBLISHED if (ROOT / name).is_dir()]
    problems = []
    for folder in folders:
        if not folder.is_dir():
            ap.error(f"{folder}: not a folder")
        if args.check:
            found = check_folder(folder)
            problems += found
            print(f"{folder / MANIFEST}: {'ok' if not found else f'{len(found)} problem(s)'}")
        else:
            print(f"{write_manifest(folder)}: {len(listed_files(folder))} files")
    for line in problems:
        print(line, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
