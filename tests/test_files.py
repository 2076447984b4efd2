"""Atomic, durable writes: the new content is flushed to disk before it replaces the old file, and
the folder is flushed after the rename; an error leaves the old file and no temporary file. The
spy below wraps the real os.fsync / os.replace (they still run) and records what they were given."""
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from spreadmap.case.launcher import write_json_atomically
from spreadmap.case.vtk_export import write_vtk
from spreadmap.files import atomic_path, write_text_atomically
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


def check_durable(events, path: Path):
    """The file's final content was flushed, then renamed over `path`, then the folder flushed."""
    path = path.resolve()
    renames = [i for i, e in enumerate(events) if e[0] == "replace" and e[2].resolve() == path]
    assert len(renames) == 1, events
    i = renames[0]
    tmp = events[i][1].resolve()
    assert tmp.parent == path.parent and tmp.name.startswith(".")  # beside the target, hidden
    flushed = [e for e in events[:i] if e[0] == "fsync" and e[1] == tmp]
    assert flushed and flushed[-1][2] == path.read_bytes()  # the whole new content, before the rename
    assert ("fsync", path.parent, None) in events[i + 1:]  # the rename itself made durable
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]  # no temporary file left


def test_text_is_flushed_before_the_rename_and_the_folder_after(disk_events, tmp_path):
    target = tmp_path / "sub" / "a.txt"
    write_text_atomically(target, "old")
    disk_events.clear()
    write_text_atomically(target, "new content\n")
    assert target.read_text() == "new content\n"
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
