"""README.md's numbers (and the guide's claims of what is current) against the published tables under
docs/ and the shipped config (issues 52, 65): tools/readme_numbers.py on the committed tables, and the
check's own rules (rounding, a wrong number, a lost phrase)."""
from __future__ import annotations

import subprocess
import sys

import pytest
from conftest import ROOT

from spreadlab.readme_numbers import CLAIMS, Claim, check, check_pages, tolerance

DOCS = ROOT / "docs"


def test_every_readme_number_rounds_to_what_the_tables_give():
    """The test of issue 52: a README number its tables do not give, or a phrase README lost, fails
    here with the number, the derived one and its source."""
    rows = check((ROOT / "README.md").read_text(), DOCS)
    bad = [f"{r.status}: README {r.stated}, derived {r.derived:.5g} ({r.label}; {r.source})"
           for r in rows if r.status != "ok"]
    assert not bad, "\n".join(bad)
    readme_numbers = sum(c.phrase.count("{}") for c in CLAIMS if c.page == "README.md")
    assert len(rows) == readme_numbers >= 50  # every claim found, each with its numbers


def test_every_guide_claim_of_what_is_current_rounds_to_what_the_tables_give():
    """The guide's numbers of the shipped run, its replay and the config (guide 3, guide 5, the index)."""
    rows = check_pages(ROOT, DOCS)
    bad = [f"{r.status}: page {r.stated}, derived {r.derived:.5g} ({r.label}; {r.source})"
           for r in rows if r.status != "ok"]
    assert not bad, "\n".join(bad)
    assert {c.page for c in CLAIMS} >= {"README.md", "docs/guide/03-convergence.md", "docs/guide/05-decisions.md"}
    assert len(rows) == sum(c.phrase.count("{}") for c in CLAIMS)


def test_a_guide_number_changed_fails_the_check(tmp_path):
    """A guide page's stale number fails like README's: guide 3 saying batches of 16 again."""
    guide = tmp_path / "docs" / "guide"
    guide.mkdir(parents=True)
    for page in {c.page for c in CLAIMS}:
        (tmp_path / page).write_text((ROOT / page).read_text())
    three = tmp_path / "docs/guide/03-convergence.md"
    three.write_text(three.read_text().replace("then batches of 8, half", "then batches of 16, half"))
    rows = check_pages(tmp_path, DOCS)
    assert [(r.stated, r.status) for r in rows if r.status != "ok"] == [("16", "MISMATCH")]


def test_a_readme_number_changed_by_one_digit_fails_the_check():
    """The check is not vacuous: the committed README with one of its numbers changed fails."""
    readme = (ROOT / "README.md").read_text()
    assert "**21.6 min**" in readme
    rows = check(readme.replace("**21.6 min**", "**20.6 min**"), DOCS)
    assert [r.stated for r in rows if r.status == "MISMATCH"] == ["20.6"]
    rows = check(readme.replace("39 of 39 stops", "38 of 39 stops"), DOCS)
    assert [r.stated for r in rows if r.status == "MISMATCH"] == ["38"]


def test_the_tool_prints_the_check_and_exits_zero_on_the_committed_tables():
    out = subprocess.run([sys.executable, "tools/readme_numbers.py"], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    assert out.stdout.strip().endswith("0 not matching or not found")
    assert "docs/main_job/run_2026-12-07e/cases.csv" in out.stdout


def test_tolerance_is_half_a_unit_of_the_last_printed_digit():
    assert tolerance("23") == pytest.approx(0.5)
    assert tolerance("1.41") == pytest.approx(0.005)
    assert tolerance("0.0096") == pytest.approx(0.00005)


def test_a_wrong_number_is_a_mismatch_and_a_lost_phrase_not_found(tmp_path):
    claim = Claim("cases", "ran {} cases, max / median {}", "cases.csv", lambda docs: [96, 22.74])
    ok = check("The job ran 96\ncases, max / median 23.", tmp_path, [claim])
    assert [r.status for r in ok] == ["ok", "ok"]
    wrong = check("The job ran 96 cases, max / median 17.", tmp_path, [claim])
    assert [r.status for r in wrong] == ["ok", "MISMATCH"]
    assert wrong[1].stated == "17"
    finer = check("The job ran 96 cases, max / median 22.7.", tmp_path, [claim])
    assert [r.status for r in finer] == ["ok", "ok"]
    finest = check("The job ran 96 cases, max / median 22.70.", tmp_path, [claim])  # 22.74 is not 22.70
    assert finest[1].status == "MISMATCH"
    assert check("The job ran many cases.", tmp_path, [claim])[0].status == "NOT FOUND"
