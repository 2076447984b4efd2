"""The house's rules a reader relies on (issue 52): the venv installs the package, so no script
reaches it by editing sys.path; and no two modules of the package share a name, so a traceback's
file name says which module it is."""
import re
from collections import Counter

from conftest import ROOT

SCRIPT_FOLDERS = ("tools", "benchmarks", "scripts", "spreadmap")


def test_no_script_or_module_edits_sys_path():
    edits = re.compile(r"sys\.path\.(insert|append|extend)\(")
    found = [str(p.relative_to(ROOT)) for folder in SCRIPT_FOLDERS for p in (ROOT / folder).rglob("*.py")
             if edits.search(p.read_text())]
    assert not found, f"these files edit sys.path (the venv installs spreadmap: import it): {found}"


def test_the_package_has_no_two_modules_of_one_name():
    names = Counter(p.name for p in (ROOT / "spreadmap").rglob("*.py") if p.name != "__init__.py")
    assert not [n for n, k in names.items() if k > 1], sorted(n for n, k in names.items() if k > 1)
