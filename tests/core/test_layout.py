"""The house's rules a reader relies on (issue 52): the venv installs the packages, so no script
reaches them by editing sys.path; and no two modules of the packages (spreadmap, and the lab beside
it, spreadlab: issue 65) share a name, so a traceback's file name says which module it is."""
import re
from collections import Counter

from conftest import ROOT

PACKAGES = ("spreadmap", "spreadlab")
SCRIPT_FOLDERS = ("tools", "benchmarks", "scripts", *PACKAGES)


def test_no_script_or_module_edits_sys_path():
    edits = re.compile(r"sys\.path\.(insert|append|extend)\(")
    found = [str(p.relative_to(ROOT)) for folder in SCRIPT_FOLDERS for p in (ROOT / folder).rglob("*.py")
             if edits.search(p.read_text())]
    assert not found, f"these files edit sys.path (the venv installs spreadmap: import it): {found}"


def test_the_packages_have_no_two_modules_of_one_name():
    names = Counter(p.name for package in PACKAGES for p in (ROOT / package).rglob("*.py") if p.name != "__init__.py")
    assert not [n for n, k in names.items() if k > 1], sorted(n for n, k in names.items() if k > 1)


NOT_ROOMS = {"core", "workflow", "benchmarks", "docs", "data"}  # tests/ folders that mirror no subpackage


def test_tests_mirror_the_packages_rooms():
    """Every subpackage of spreadmap and spreadlab has a tests/ folder of its name holding a test
    file (a room of one name in both, noise_law, shares one), and every tests/ folder but the few
    that test no room (core: the top-level modules) names a subpackage."""
    rooms = {p.parent.name for package in PACKAGES for p in (ROOT / package).glob("*/__init__.py")}
    folders = {p.name for p in (ROOT / "tests").iterdir() if p.is_dir() and not p.name.startswith((".", "_"))}
    no_tests = sorted(r for r in rooms if not list((ROOT / "tests" / r).glob("test_*.py")))
    assert not no_tests, f"subpackages without a tests/ folder of their name holding a test file: {no_tests}"
    strays = sorted(folders - rooms - NOT_ROOMS)
    assert not strays, f"tests/ folders that name no subpackage of spreadmap or spreadlab: {strays}"
