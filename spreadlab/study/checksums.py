"""Checksums of published results: a published folder under docs/ holds a manifest, SHA256SUMS,
in the format of coreutils' `sha256sum` (one `<sha256>  <path>` line per file, paths relative to
the folder), listing its cases tables and whatever else a restore reads from it. The restore
(spreadlab/study/restore.py, tools/restore_study.py) verifies every file it reads against it before it
restores a case, so that a published table that rotted (edited by hand, truncated, corrupted) is
refused instead of restored; tools/publish_checksums.py re-makes the manifests after a publish.

One manifest per published folder rather than one for all of docs/: a folder is what a tool
publishes and what a restore reads (`restore_study.py --published FOLDER`), so it carries its own
checksums when copied elsewhere, `cd FOLDER && sha256sum -c SHA256SUMS` checks it without this
code, and re-publishing one folder rewrites its own manifest only.
"""
from __future__ import annotations

import hashlib
import re
from pathlib import Path

from spreadmap.files import write_text_atomically

MANIFEST = "SHA256SUMS"
# What a study folder's manifest lists: what tools/restore_study.py reads from it
STUDY_PATTERNS = ("cases_*.csv", "*_seeds.csv", "converge/steps/step_*.json", "heldout/*.csv")
# The published folders of this repository (relative to its root) and what each manifest lists
PUBLISHED = {
    "docs/study": STUDY_PATTERNS,
    "docs/precision": ("cases.csv",),
    "docs/fidelity": ("cases_*.csv",),
    "docs/fidelity_flat": ("cases_*.csv",),
    "docs/main_job": ("cases.csv",),
}
PUBLISH_COMMAND = ".venv/bin/python tools/publish_checksums.py"
_LINE = re.compile(r"([0-9a-f]{64}) [ *](.+)")


class PublishedFileError(ValueError):
    """A published file that does not match its manifest (or has none): the message names the
    file and how to restore or re-publish it."""


def sha256(data: bytes) -> str:
    """The SHA-256 of some bytes, as hex.

    Parameters
    ----------
    data : bytes
        The bytes (a file's content).

    Returns
    -------
    str
        64 lowercase hex digits, as ``sha256sum`` writes them.
    """
    return hashlib.sha256(data).hexdigest()


def patterns_for(folder: Path | str) -> tuple[str, ...]:
    """The manifest patterns of a folder: this repository's own list for its published folders,
    a study folder's for any other."""
    root = Path(__file__).resolve().parents[2]
    folder = Path(folder).resolve()
    for name, patterns in PUBLISHED.items():
        if folder == root / name:
            return patterns
    return STUDY_PATTERNS


def listed_files(folder: Path | str, patterns=None) -> list[str]:
    """The files of `folder` its manifest lists: relative POSIX paths, sorted.

    Parameters
    ----------
    folder : pathlib.Path or str
        The published folder.
    patterns : sequence of str or None, optional
        Glob patterns relative to the folder; None: the folder's own (this repository's list for its
        published folders, ``STUDY_PATTERNS`` for any other).

    Returns
    -------
    list of str
        The files (not folders) the patterns match, relative to the folder, sorted.
    """
    folder = Path(folder)
    found = {p.relative_to(folder).as_posix() for pattern in (patterns or patterns_for(folder))
             for p in folder.glob(pattern) if p.is_file()}
    return sorted(found)


def manifest_text(folder: Path | str, patterns=None) -> str:
    folder = Path(folder)
    return "".join(f"{sha256((folder / rel).read_bytes())}  {rel}\n" for rel in listed_files(folder, patterns))


def write_manifest(folder: Path | str, patterns=None) -> Path:
    """(Re-)make folder/SHA256SUMS from the files as they are now; returns its path.

    Parameters
    ----------
    folder : pathlib.Path or str
        The published folder.
    patterns : sequence of str or None, optional
        What the manifest lists (``listed_files``); None: the folder's own patterns.

    Returns
    -------
    pathlib.Path
        The manifest, written atomically: one ``<sha256>  <path>`` line per file listed.
    """
    path = Path(folder) / MANIFEST
    write_text_atomically(path, manifest_text(folder, patterns))
    return path


def read_manifest(manifest: Path | str) -> dict[str, str]:
    """{relative path: sha256} of a manifest; a malformed line is refused, naming its number."""
    manifest = Path(manifest)
    out = {}
    for number, line in enumerate(manifest.read_text().splitlines(), 1):
        m = _LINE.fullmatch(line)
        if not m:
            raise PublishedFileError(f"{manifest}, line {number}: not a `sha256sum` line ({line[:80]!r}); "
                                     f"re-make it: {PUBLISH_COMMAND} {manifest.parent}")
        out[m.group(2)] = m.group(1)
    return out


def find_manifest(path: Path | str) -> Path | None:
    """The manifest that covers `path`: SHA256SUMS in its folder or the nearest folder above."""
    for folder in Path(path).resolve().parents:
        if (folder / MANIFEST).is_file():
            return folder / MANIFEST
    return None


def verified_bytes(path: Path | str, required: bool = True) -> bytes:
    """The bytes of a published file, after checking them against its manifest.

    The manifest is SHA256SUMS in the file's folder or the nearest folder above it. A file no
    manifest lists is refused when `required` (a restore), read as it is otherwise (a resume from a
    CSV that was never published).

    Parameters
    ----------
    path : pathlib.Path or str
        The published file.
    required : bool, optional
        True: a file without a manifest, or not listed in it, is refused.

    Returns
    -------
    bytes
        The file's content.

    Raises
    ------
    PublishedFileError
        If the file does not match its listed checksum, its manifest has a malformed line, or
        (when `required`) no manifest lists it; the message says how to get the file back or
        re-publish the checksums.
    FileNotFoundError
        If the file is missing.
    """
    path = Path(path)
    data = path.read_bytes()
    manifest = find_manifest(path)
    if manifest is None:
        if required:
            raise PublishedFileError(
                f"{path}: no {MANIFEST} beside it or above it, so nothing says it is the file that was published; "
                f"if you trust it, publish its checksums: {PUBLISH_COMMAND} {path.parent}")
        return data
    rel = path.resolve().relative_to(manifest.parent.resolve()).as_posix()
    sums = read_manifest(manifest)
    if rel not in sums:
        if required:
            raise PublishedFileError(f"{path} is not listed in {manifest}; if it is meant to be published, "
                                     f"re-publish the checksums: {PUBLISH_COMMAND} {manifest.parent}")
        return data
    got = sha256(data)
    if got != sums[rel]:
        raise PublishedFileError(
            f"{path} does not match its published checksum in {manifest} (SHA-256 {got[:12]}..., published "
            f"{sums[rel][:12]}...): it changed since it was published (edited, truncated or corrupted) and is not "
            f"restored. Get the published file back (`git checkout -- {path}`), or if the change is meant, "
            f"re-publish the checksums: {PUBLISH_COMMAND} {manifest.parent}")
    return data


def check_folder(folder: Path | str, patterns=None) -> list[str]:
    """What is wrong with a published folder's manifest; [] when it holds.

    One line per file that differs from it, is listed but gone, or should be listed and is not; one
    line alone when the manifest is missing or malformed.

    Parameters
    ----------
    folder : pathlib.Path or str
        The published folder.
    patterns : sequence of str or None, optional
        What the manifest should list (``listed_files``); None: the folder's own patterns.

    Returns
    -------
    list of str
        The problems, each naming the file; [] when the manifest holds.
    """
    folder = Path(folder)
    manifest = folder / MANIFEST
    if not manifest.is_file():
        return [f"{folder}: no {MANIFEST}; make it: {PUBLISH_COMMAND} {folder}"]
    try:
        sums = read_manifest(manifest)
    except PublishedFileError as error:
        return [str(error)]
    problems = []
    for rel, want in sums.items():
        if not (folder / rel).is_file():
            problems.append(f"{folder / rel}: listed in {manifest} but missing")
        elif sha256((folder / rel).read_bytes()) != want:
            problems.append(f"{folder / rel}: does not match {manifest}")
    problems += [f"{folder / rel}: not listed in {manifest}" for rel in listed_files(folder, patterns) if rel not in sums]
    return problems


def republish_if_listed(path: Path | str) -> Path | None:
    """After a tool rewrote a published file: re-make the manifest that lists it (none: nothing).

    Parameters
    ----------
    path : pathlib.Path or str
        The file rewritten.

    Returns
    -------
    pathlib.Path or None
        The manifest re-made (``write_manifest`` of its folder); None when no manifest covers the
        file or it does not list it.

    Raises
    ------
    PublishedFileError
        If the manifest covering the file has a malformed line.
    """
    manifest = find_manifest(path)
    if manifest is None:
        return None
    rel = Path(path).resolve().relative_to(manifest.parent.resolve()).as_posix()
    if rel not in read_manifest(manifest):
        return None
    return write_manifest(manifest.parent)
