"""README.md and the guide (docs/guide/*.md) present as current only what runs on the shipped scene
(issue 65, item 5).

The shipped scene dates from 2026-12-07 (commit 44ca9cf: the window 5 d beyond the pile on a pile
of 3 d, the overlap read twice a contact). The main job's runs ``run_2026-12-07e`` and later are on
it; ``run_2026-12-07``, ``07b``, ``07c``, ``07c_again``, ``07d`` and every earlier run are not, and
neither is any result dated before 2026-12-07.

The convention these tests hold the pages to:

1. **A figure names its run and its powder in its alt text** (the markdown caption,
   ``![alt](path)``): a main-job run folder (``run_2026-12-07e``) or, for a figure of another
   published folder, the date it was made (``2026-12-01``); and the powder, ``dry`` or
   ``adhesive`` (``no DEM`` for a DEM-free study). The rule graph is not a result and is exempt.
2. **A figure of a run before the shipped scene is marked as history**: its alt text says
   ``history`` (or ``before the shipped scene``). A figure is current only if it names a run folder
   from ``run_2026-12-07e`` on, or a date after 2026-12-07.
3. **A run cited in the text** (``run_2026-12-04``, ``the run of 2026-12-01``, ``the main job of
   2026-12-06``, ``the 2026-12-01 run``) **from before the shipped scene sits in a sentence, list item or section marked as
   history**: the sentence (or the enclosing list item, or one of its headings) contains
   ``history``/``historical``, ``before the shipped scene`` or ``the scene before``.
   Everything else on these pages is read as current.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]
SHIPPED = ("2026-12-07", "e")  # the first run on the shipped scene: run_2026-12-07e
NOT_RESULTS = {"rulegraph.png"}  # figures that show no result: the workflow's DAG

IMAGE = re.compile(r"!\[([^\]]*)\]\(([^)\s]+)\)")
RUN_FOLDER = re.compile(r"run_(\d{4}-\d{2}-\d{2})([a-z]?)(\w*)")
DATE = re.compile(r"\b(\d{4}-\d{2}-\d{2})\b")
RUN_OF_DATE = re.compile(r"\b(?:run|runs|job)\s+(?:of|on|from)\s+(\d{4}-\d{2}-\d{2})\b"
                         r"|\b(\d{4}-\d{2}-\d{2})(?:'s)?\s+(?:main job|run)\b")
POWDER = re.compile(r"\b(dry|adhesive|no DEM)\b")
HISTORY = re.compile(r"\bhistor(?:y|ical)\b|before the shipped scene|the scene before", re.IGNORECASE)


def on_shipped_scene(date: str, suffix: str = "") -> bool:
    """A run folder's date and letter (``run_2026-12-07e`` -> "2026-12-07", "e") on the shipped scene."""
    return date > SHIPPED[0] or (date == SHIPPED[0] and suffix >= SHIPPED[1])


def figures(text: str) -> list[tuple[str, str]]:
    return IMAGE.findall(text)


def figure_problem(alt: str, path: str) -> str | None:
    """Why a figure breaks the convention (1, 2), or None."""
    if Path(path).name in NOT_RESULTS:
        return None
    runs, dates = RUN_FOLDER.findall(alt + " " + path), DATE.findall(alt)
    if not runs and not dates:
        return "names no run folder and no date"
    if not POWDER.search(alt):
        return "names no powder (dry / adhesive / no DEM)"
    current = any(on_shipped_scene(d, s) for d, s, _ in runs) or (not runs and any(d > SHIPPED[0] for d in dates))
    if not current and not HISTORY.search(alt):
        return "shows a run before the shipped scene without marking it as history"
    return None


def sections(text: str):
    """(heading chain, block) for every paragraph or list item of a markdown page, code blocks left out."""
    headings: list[tuple[int, str]] = []
    block: list[str] = []
    fenced = False

    def flush():
        if block:
            yield " / ".join(h for _, h in headings), " ".join(" ".join(block).split())
        block.clear()

    for line in text.split("\n"):
        if line.startswith("```"):
            fenced = not fenced
            yield from flush()
            continue
        if fenced:
            continue
        m = re.match(r"(#+)\s+(.*)", line)
        if m:
            yield from flush()
            level = len(m[1])
            headings = [h for h in headings if h[0] < level] + [(level, m[2])]
        elif not line.strip() or re.match(r"\s*(?:[-*]|\d+\.)\s", line):
            yield from flush()
            if line.strip():
                block.append(line)
        else:
            block.append(line)
    yield from flush()


def sentences(block: str) -> list[str]:
    return re.split(r"(?<=[.!?])\s+(?=[A-Z*(\[`])", block)


def stale_citations(text: str) -> list[str]:
    """Runs from before the shipped scene cited as current (convention 3), each with its sentence."""
    bad = []
    for heading, block in sections(text):
        prose = IMAGE.sub("", block)
        block_history = HISTORY.search(heading) or (block.lstrip().startswith(("-", "*")) and HISTORY.search(prose))
        for sentence in sentences(prose):
            old = [f"run_{d}{s}{rest}" for d, s, rest in RUN_FOLDER.findall(sentence) if not on_shipped_scene(d, s)]
            old += [f"run of {a or b}" for a, b in RUN_OF_DATE.findall(sentence) if (a or b) < SHIPPED[0]]
            if old and not (block_history or HISTORY.search(sentence)):
                bad.append(f"{', '.join(old)}: {sentence[:160]}")
    return bad


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_figure_names_its_run_and_powder_and_marks_an_old_run_as_history(page):
    bad = [f"![{alt}]({path}): {why}" for alt, path in figures(page.read_text())
           if (why := figure_problem(alt, path))]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_no_run_before_the_shipped_scene_is_cited_as_current(page):
    bad = stale_citations(page.read_text())
    assert not bad, "\n".join(bad)


def test_the_front_figure_is_a_run_on_the_shipped_scene():
    (alt, path), *_ = figures((ROOT / "README.md").read_text())
    run = RUN_FOLDER.search(path)
    assert run and on_shipped_scene(run[1], run[2]), path
    assert (ROOT / path).is_file()
    assert "adhesive" in alt and "`default`" in alt and "density x1000" in alt


def test_the_convention_catches_an_old_run_presented_as_current():
    """The checks fail on what they are for: the former front figure and paragraph."""
    old_figure = ("machine map of the main job's run of 2026-12-04 (96 cases), MFR read as `reference`",
                  "docs/main_job/run_2026-12-04/machine_map_corrected.png")
    assert figure_problem(*old_figure) == "names no powder (dry / adhesive / no DEM)"
    assert figure_problem(old_figure[0] + ", dry", old_figure[1]).startswith("shows a run before")
    assert figure_problem(old_figure[0] + ", dry: history", old_figure[1]) is None
    assert figure_problem("the shipped run's map, adhesive", "docs/main_job/run_2026-12-07e/machine_map.png") is None
    assert figure_problem("the run c's map, adhesive", "docs/main_job/run_2026-12-07c_again/timeline.png")
    assert figure_problem("a map", "docs/figures/machine_map.png") == "names no run folder and no date"
    page = "## Results\n\nThe main job's run of 2026-12-04 stopped at 96 cases. The shipped run is run_2026-12-07e.\n"
    assert stale_citations(page) == ["run of 2026-12-04: The main job's run of 2026-12-04 stopped at 96 cases."]
    assert stale_citations(page.replace("## Results", "## History")) == []
    assert stale_citations(page.replace("stopped at", "(history) stopped at")) == []
    assert stale_citations("- run_2026-12-07d was stopped by hand. History, not shipped.\n") == []
    assert stale_citations("- run_2026-12-07d was stopped by hand. It is shipped.\n")
    assert stale_citations("```\nrun_2026-12-04\n```\n") == []
    assert stale_citations("The 2026-12-01 run's ranking is below.\n")
    assert stale_citations("The main job's run on 2026-12-08 is below.\n") == []
