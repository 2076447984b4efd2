"""Atomic, durable file writes: write beside the target, flush it to disk (fsync), rename it over
the target, then flush the folder (so the rename itself survives a power cut). A reader, a run
killed half-way or a machine that loses power never sees a partial or empty file: it sees the
old file or the new one. A full disk or a file-size limit met while writing leaves the old file
too, and the error says so, naming the file."""
from __future__ import annotations

import csv
import errno
import io
import os
import uuid
from contextlib import contextmanager
from pathlib import Path


def fsync_path(path: Path | str) -> None:
    """Flush a file's (or a folder's) data and metadata to disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


# errors of a write that ran out of room: no space left, a disk quota, a file-size limit
DISK_FULL = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


@contextmanager
def atomic_path(path: Path | str):
    """Yield a temporary path beside `path` to write to; on success it replaces `path` in one rename.

    On success the temporary file is flushed to disk and replaces `path` in one rename (then the
    folder is flushed). On an error it is removed and `path` is left as it was. The temporary name
    is a dot file unique to the process and call, so that globs of the folder do not see it.

    Parameters
    ----------
    path : pathlib.Path or str
        The file to write; its folder is created if missing.

    Yields
    ------
    pathlib.Path
        The temporary path to write the whole file to.

    Raises
    ------
    OSError
        A full disk (ENOSPC, EDQUOT) or a file-size limit (EFBIG) is raised as an OSError of the
        same errno whose message names `path` and says so; any other error as it is.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # unique per process and call (two threads of one process never share it); a dot file, so
    # that globs of the folder's results do not see it
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    replaced = False
    try:
        yield tmp
        fsync_path(tmp)
        os.replace(tmp, path)
        replaced = True
        fsync_path(path.parent)
    except OSError as error:
        if replaced or error.errno not in DISK_FULL:
            raise
        raise OSError(error.errno, f"{os.strerror(error.errno)} while writing {path}: the disk is full or a "
                                   f"file-size limit (ulimit -f) was hit; {path} was left as it was and the partial "
                                   f"copy beside it removed") from error
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text_atomically(path: Path | str, text: str, encoding: str = "utf-8") -> None:
    """Write text to a file atomically and durably (``atomic_path``).

    Parameters
    ----------
    path : pathlib.Path or str
        The file; its folder is created if missing.
    text : str
        The whole content, written as it is (no newline translation).
    encoding : str, optional
        The text encoding.

    Raises
    ------
    OSError
        If the write fails (``atomic_path``: a full disk or a file-size limit named as such); the
        file is left as it was.
    """
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding=encoding, newline="\n") as fh:
            fh.write(text)


def write_csv_atomically(path: Path | str, rows, columns) -> None:
    """Write rows as a CSV table atomically and durably (``write_text_atomically``).

    Parameters
    ----------
    path : pathlib.Path or str
        The file; its folder is created if missing.
    rows : iterable of dict
        One mapping per row, column name to value (written as ``csv.DictWriter`` writes it).
    columns : iterable of str
        The header, in order; a row's other keys are left out, a column a row lacks is empty.

    Raises
    ------
    OSError
        If the write fails (``atomic_path``); the file is left as it was.
    """
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(columns), extrasaction="ignore")
    writer.writeheader()
    writer.writerows(rows)
    write_text_atomically(path, buf.getvalue())
