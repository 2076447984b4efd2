"""Atomic, durable writes: the new content is flushed to disk before it replaces the old file, and
the folder is flushed after the rename; an error leaves the old file and no temporary file. The
spy below wraps the real os.fsync / os.replace (they still run) and records what they were given."""
import os
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT

from spreadmap.case.launcher import write_json_atomically
from spreadmap.case.vtk_export import write_vtk
from spreadmap.figures import new_figure, save_figure
from spreadmap.files import atomic_path, write_csv_atomically, write_text_atomically
from spreadmap.table import write_table


@pytest.fixture
def disk_events(monkeypatch):
    events = []
    real_fsync, real_replace = os.fsync, os.replace

    def fsync(fd):
        target = Path(os.readlink(f"/proc/self/fd/{fd}"))
        events.append(("fsync", target, target.read_bytes() if target.is_file() else None))
        return real_fsync(fd)

    def replace(src, dst, *args, **kwargs):
        events.append(("replace", Path(src), Path(dst)))
        return real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(os, "replace", replace)
    return events


def check_durable(events, path: Path, alone: bool = True):
    """The file's final content was flushed, then renamed over `path`, then the folder flushed
    (`alone`: and it is the only file in its folder, no temporary file left)."""
    path = path.resolve()
    renames = [i for i, e in enumerate(events) if e[0] == "replace" and e[2].resolve() == path]
    assert len(renames) == 1, events
    i = renames[0]
    tmp = events[i][1].resolve()
    assert tmp.parent == path.parent and tmp.name.startswith(".")  # beside the target, hidden
    flushed = [e for e in events[:i] if e[0] == "fsync" and e[1] == tmp]
    assert flushed and flushed[-1][2] == path.read_bytes()  # the whole new content, before the rename
    assert ("fsync", path.parent, None) in events[i + 1:]  # the rename itself made durable
    if alone:
        assert sorted(p.name for p in path.parent.iterdir()) == [path.name]  # no temporary file left


def test_text_is_flushed_before_the_rename_and_the_folder_after(disk_events, tmp_path):
    target = tmp_path / "sub" / "a.txt"
    write_text_atomically(target, "old")
    disk_events.clear()
    write_text_atomically(target, "new content\n")
    assert target.read_text() == "new content\n"
    check_durable(disk_events, target)


def test_rows_are_written_as_a_csv_through_the_durable_helper(disk_events, tmp_path):
    """The columns in the order given, a row's other keys left out and a missing one empty."""
    target = tmp_path / "rows" / "arms.csv"
    write_csv_atomically(target, [{"b": 1, "a": "x", "extra": 9}, {"a": "y"}], ["a", "b"])
    assert target.read_bytes() == b"a,b\r\nx,1\r\ny,\r\n"
    check_durable(disk_events, target)


def test_every_writer_goes_through_the_durable_helper(disk_events, tmp_path):
    """The raw records, the results tables and the VTK files (which had their own copy of the
    helper, without the folder's flush)."""
    write_json_atomically(tmp_path / "json" / "raw.json", {"status": "ok"})
    check_durable(disk_events, tmp_path / "json" / "raw.json")
    write_table(pd.DataFrame({"a": [1, 2]}), tmp_path / "table" / "t.csv")
    check_durable(disk_events, tmp_path / "table" / "t.csv")
    snap = {"positions": np.zeros((2, 3)).tolist(), "radii": [1e-5, 1e-5], "velocities": np.ones((2, 3)).tolist()}
    write_vtk(snap, tmp_path / "vtk" / "end.vtk")
    check_durable(disk_events, tmp_path / "vtk" / "end.vtk")


def test_an_error_while_writing_leaves_the_old_file(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("killed half-way")
    assert target.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["a.txt"]


def _figure():
    fig = new_figure(4, 3)
    fig.add_subplot(111).plot([0, 1], [1, 0])
    return fig


def test_a_figure_and_its_table_go_through_the_durable_helper(disk_events, tmp_path):
    """Every map, study and case figure is saved by spreadmap.figures.save_figure: its PNG, PDF
    and CSV each flushed beside the target and renamed over it."""
    paths = save_figure(_figure(), tmp_path / "fig", pd.DataFrame({"a": [1.0]}))
    for path in paths.values():
        check_durable(disk_events, path, alone=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.csv", "fig.pdf", "fig.png"]


def test_a_figure_that_fails_half_way_leaves_the_old_files(tmp_path):
    old = save_figure(_figure(), tmp_path / "fig", pd.DataFrame({"a": [1.0]}))
    before = {ext: path.read_bytes() for ext, path in old.items()}
    fig = _figure()

    def savefig(target, **kwargs):  # a run killed while the PNG is being written
        Path(target).write_bytes(before["png"][:100])
        raise KeyboardInterrupt("killed half-way")

    fig.savefig = savefig
    with pytest.raises(KeyboardInterrupt):
        save_figure(fig, tmp_path / "fig", pd.DataFrame({"a": [2.0]}))
    assert {ext: path.read_bytes() for ext, path in old.items()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.csv", "fig.pdf", "fig.png"]


# writes in spreadmap/ and scripts/ that are not workflow outputs, and why they stay direct
DIRECT_WRITES = {
    ("spreadmap/logs.py", "open(smk.log[0]"): "a job's log, streamed line by line while it runs",
    ("spreadmap/surrogate/cli.py", "Path(smk.log[0]).write_text"): "predict's log",
    ("spreadmap/case/launcher.py", 'open(log_path, "w")'): "the YADE run's log, streamed",
    ("spreadlab/experiments/noisy_study.py", "to_csv(partial"): "progress of a long experiment, a scratch file",
}
WRITE = re.compile(r"""\.(to_csv|write_text|write_bytes|savefig)\((?!tmp\b|index=)|json\.dump\(|open\([^)]*["'][wa]b?["']""")


def test_outputs_are_written_only_through_the_atomic_helpers():
    """No output of the packages (the lab's too) or of a Snakemake script is written in place (a run killed
    half-way would leave a truncated CSV, JSON or figure that looks finished); writes inside an
    atomic_path (to its `tmp`) are the helper's own."""
    root = ROOT
    found = []
    for path in sorted([*root.glob("spreadmap/**/*.py"), *root.glob("spreadlab/**/*.py"), *root.glob("scripts/*.py")]):
        name = str(path.relative_to(root))
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if WRITE.search(line) and "tmp" not in line and not any(
                    name == file and text in line for file, text in DIRECT_WRITES):
                found.append(f"{name}:{number}: {line.strip()}")
    assert not found, "\n".join(found)
