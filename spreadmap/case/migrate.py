"""Case folders named before content keys (issue 35) renamed to their content ids, without re-running.

Before issue 35 a case id was `<preset>-f..-d..-h..-v..-s<seed>` (spreadmap.case.identity.LEGACY_CASE_ID_PATTERN):
it did not say which material, scene or template version the case was run with. A legacy folder whose
parameters are recorded in it is keyed exactly: the raw record's `params` (raw.json, or the launcher's
simulated.json: what the YADE script ran with), else the PARAMS block of its rendered case.py (what it
was rendered with; a folder with only case.py had not run). Its new id is its old one plus the content
key of those parameters (spreadmap.case.identity.content_key), so a case run with the current configuration
and template is found again by the workflow, and one run with another material or template sits
beside the current ones under its own id. The id recorded inside its text files (params.case_id, the
metrics' case_id, the case.py header, the logs' prefixes) is rewritten to the new one; every file
keeps its modification time, so that Snakemake sees the case as up to date.

A folder it cannot key (no parameters recorded: a case restored from a published table, or one that
never rendered; parameters that do not name the folder's own case) is left where it is and reported,
never deleted; so is a folder whose content id is already taken.

A legacy folder gets the content id of its day (the key of issue 35, over every parameter but the id
and the template's bytes) unless it records today's template; ``carry_to_code_keys`` then carries
it, with every case keyed that way, to the key of issue 65 (what it simulates, the template's code).
"""
from __future__ import annotations

import json
import os
import re
from pathlib import Path

from ..files import write_text_atomically
from .identity import CASE_ID_PATTERN, LEGACY_CASE_ID_PATTERN, NAMING_FIELDS, keyed_id, readable_id
from .render import rendered_params, template_sha256
from .scene import overlap_stride

# The files of a case folder that may record its id, rewritten in place (others, e.g. pictures, are moved untouched).
TEXT_SUFFIXES = (".py", ".json", ".log", ".txt", ".tsv", ".csv")
_LEGACY = re.compile(LEGACY_CASE_ID_PATTERN)


def legacy_case_folders(cases_dir: Path | str) -> list[Path]:
    """The folders of cases_dir named by a legacy case id (sorted).

    Parameters
    ----------
    cases_dir : pathlib.Path or str
        The cases' folder (results/cases).

    Returns
    -------
    list of pathlib.Path
        The sub-folders whose whole name matches ``LEGACY_CASE_ID_PATTERN``, sorted; [] when
        cases_dir is not a folder.
    """
    cases_dir = Path(cases_dir)
    if not cases_dir.is_dir():
        return []
    return sorted(p for p in cases_dir.iterdir() if p.is_dir() and _LEGACY.fullmatch(p.name))


def recorded_params(folder: Path) -> tuple[dict | None, str]:
    """(the parameters a case folder records, where from) or (None, why not)."""
    for name in ("raw.json", "simulated.json"):
        try:
            params = json.loads((folder / name).read_text()).get("params")
        except (OSError, ValueError, AttributeError):
            continue
        if isinstance(params, dict):
            return params, name
    try:
        text = (folder / "case.py").read_text()
    except OSError:
        return None, "no raw record and no case.py"
    try:
        return rendered_params(text), "case.py"
    except ValueError as error:
        return None, f"case.py: {error}"


def new_id(folder: Path) -> tuple[str | None, str]:
    """(the content id of a legacy case folder, where its parameters came from) or (None, why not)."""
    params, source = recorded_params(folder)
    if params is None:
        return None, source
    try:
        # the key of its day (issue 35's, over the template's bytes); today's for today's template
        left_out = None if params.get("scene_sha256") == template_sha256() else NAMING_FIELDS
        named = readable_id(params["point"], params["preset"], params["seed"])
        keyed = keyed_id(params) if left_out is None else keyed_id(params, left_out)
        # (a case_id already rewritten to the content id: a migration interrupted before the rename)
        if named != folder.name or params.get("case_id") not in (folder.name, keyed):
            return None, f"the parameters in {source} are of case {params.get('case_id')!r}, not of this folder"
        return keyed, source
    except (KeyError, TypeError, ValueError) as error:
        return None, f"the parameters in {source} cannot be keyed ({type(error).__name__}: {error})"


def _rewrite_ids(folder: Path, old: str, new: str) -> list[str]:
    """Replace the old id by the new one in the folder's text files (an id, not a longer id it
    begins), keeping each file's modification time. Returns the files changed."""
    pattern = re.compile(re.escape(old) + r"(?![\w.-])")
    changed = []
    for path in sorted(folder.rglob("*")):
        if not path.is_file() or path.suffix not in TEXT_SUFFIXES:
            continue
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError):
            continue
        replaced = pattern.sub(new, text)
        if replaced != text:
            stat = path.stat()
            write_text_atomically(path, replaced)
            os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
            changed.append(str(path.relative_to(folder)))
    return changed


def migrate_case_folders(cases_dir: Path | str, dry_run: bool = False) -> dict:
    """Rename every legacy case folder of cases_dir that can be keyed to its content id; leave the others.

    The id inside its text files (``TEXT_SUFFIXES``) is rewritten too, and every file and the folder
    keep their modification times (see the module docstring). A folder that cannot be keyed, or whose
    content id is taken already, is left where it is and reported.

    Parameters
    ----------
    cases_dir : pathlib.Path or str
        The cases' folder (results/cases).
    dry_run : bool, optional
        True: report what would be renamed, change nothing.

    Returns
    -------
    dict
        ``{"renamed": [(old, new, source)], "left": [(old, why)]}``: the old and new folder names,
        where the parameters came from (raw.json, simulated.json or case.py), and why a folder was
        left.
    """
    cases_dir = Path(cases_dir)
    report = {"renamed": [], "left": []}
    for folder in legacy_case_folders(cases_dir):
        new, source = new_id(folder)
        if new is None:
            report["left"].append((folder.name, source))
            continue
        if _rename_case(folder, new, dry_run, report):
            report["renamed"].append((folder.name, new, source))
    return report


def _rename_case(folder: Path, new: str, dry_run: bool, report: dict) -> bool:
    """Rename a case folder to the id `new`, the id inside its text files with it, keeping the
    modification times; False (and the folder left, reported) when `new` exists already."""
    target = folder.parent / new
    if target.exists():
        report["left"].append((folder.name, f"{new} exists already"))
        return False
    if not dry_run:
        stat = folder.stat()
        _rewrite_ids(folder, folder.name, new)
        folder.rename(target)
        os.utime(target, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    return True


# The scene templates keyed by their bytes (issue 35 to issue 65) whose cases today's template code
# simulates identically, given the parameters added since: {template's bytes sha256 (16 hex): the
# added parameters}. The template before adhesion (issue 49) and the later ones with surface energy 0
# give the same MFR and PD to the bit (tests/case/test_reproduce_published_yade.py); the adhesion
# change only added adhesion and dropped the monitor's overlap scan (a diagnostic record_overlap
# makes at every sampled step). 0ae31d5c9de2bce9 is the adhesion template before a correction of its
# comments (the main job of 2026-12-06 ran on it), e9640a66ef79dc3a the one after; the size
# distribution (issue 51) added its parameters, and with a span of 0 (one size) takes the one-size
# path of the earlier templates to the bit (the same test); 7069f5e574fa3095 is the last template
# keyed by its bytes. The list is closed: since issue 65 a case is keyed by the template's code
# (spreadmap.case.render.template_sha256), which a comment does not change.
ONE_SIZE = {"size_span": 0.0, "psd_sizes": [], "psd_cumulative": []}
BYTE_HASHED_TEMPLATES = {
    "2faa01e6a62c2a28": {"surface_energy": 0.0, "adhesion_gamma": 0.0, **ONE_SIZE},
    "0ae31d5c9de2bce9": ONE_SIZE,
    "e9640a66ef79dc3a": ONE_SIZE,
    "7069f5e574fa3095": {},
}
# Parameters every one of them gets: those the scene added since 7069f5e574fa3095, at the values that
# simulate what it did (issue 64: the side walls adhesive, as every contact was).
ADDED_SINCE_BYTES = {"side_walls_adhesive": True}
# The code hash of the template they are carried to: the one shipped with issue 65's key, in the same
# batch as the side walls' option and the jam record (issue 66: it only reads the contacts, the published
# median case's MFR and PD the same to the bit). A later change of the template's code re-keys every
# case, these too (their ids stay those of this code).
CARRIED_TO = "904561580543e6e3"


def with_todays_stride(params: dict, reads_per_contact: int) -> dict:
    """The parameters with today's overlap stride (spreadmap.case.scene.overlap_stride): a case that
    read the peak overlap more often (every step, before issue 50) simulated the same spheres to the
    bit (benchmarks/overlap_stride.py) and held its stability check to the per-step record, at least
    as strict; records without the stride are returned as they are. The stride is never made finer
    than the record's: a case cannot be carried to a read it did not make, and a preset may read
    less often than its preset asks (`reads_per_contact`, the config's overlap_reads_per_contact of the
    case's preset: 2 at the shipped `default` since 2026-12-07, 4 before, 3 at the tests' `smoke`)."""
    if "overlap_every" not in params or "contact_time" not in params:
        return params
    today = overlap_stride(params["contact_time"], params["time_step"], int(reads_per_contact))
    return {**params, "overlap_every": max(int(params["overlap_every"]), today)}


def _named_by(folder: Path, params: dict, reads_per_contact: int) -> bool:
    """Whether a folder is named by the key of issue 35 of its recorded parameters: as they are, or
    as an earlier carry (to 7069f5e574fa3095, the added parameters and today's stride) named it
    while its record kept the ones it ran with."""
    earlier = with_todays_stride({**params, **BYTE_HASHED_TEMPLATES[params["scene_sha256"]],
                                  "scene_sha256": "7069f5e574fa3095"}, reads_per_contact)
    return folder.name in (keyed_id(params, NAMING_FIELDS), keyed_id(earlier, NAMING_FIELDS))


def carry_to_code_keys(cases_dir: Path | str, config: dict, dry_run: bool = False) -> dict:
    """Re-key, once, the finished cases named by the key of issue 35 (over the template's bytes) of
    a template today's code simulates identically (``BYTE_HASHED_TEMPLATES``) to the key of issue 65
    (what a case simulates: the template's code ``CARRIED_TO``, without the bookkeeping fields), and
    those that read the peak overlap at another stride to today's (``with_todays_stride``).

    (The adhesive cases of template 0ae31d5c9de2bce9 keep their surface energy: only the template's
    hash and the parameters added since change in their parameters.)

    A case folder named by a content id whose recorded parameters (``recorded_params``) name a
    listed template, and whose name is their key of issue 35 (or an earlier carry's), gets the id of
    its parameters with the listed ones and ``ADDED_SINCE_BYTES`` added, ``scene_sha256`` =
    ``CARRIED_TO`` and the overlap stride today's: the id the workflow asks for while the template's
    code is ``CARRIED_TO``, so the case is not re-run. Its raw record keeps the parameters it ran
    with (its metrics read its own stride). The id inside its text files is rewritten and
    modification times kept, as ``migrate_case_folders`` does.

    Parameters
    ----------
    cases_dir : pathlib.Path or str
        The cases' folder (results/cases).
    config : dict
        The loaded configuration the cases are carried to: each case's preset's
        ``overlap_reads_per_contact`` sets today's stride (a case of a preset it lacks is left alone).
    dry_run : bool, optional
        True: report what would be renamed, change nothing.

    Returns
    -------
    dict
        ``{"renamed": [(old, new)], "left": [(old, why)]}``; folders of another template (today's
        among them) are not reported.
    """
    cases_dir = Path(cases_dir)
    report = {"renamed": [], "left": []}
    if not cases_dir.is_dir():
        return report
    for folder in sorted(p for p in cases_dir.iterdir() if p.is_dir() and re.fullmatch(CASE_ID_PATTERN, p.name)):
        params, source = recorded_params(folder)
        if params is None or params.get("scene_sha256") not in BYTE_HASHED_TEMPLATES:
            continue
        preset = config["presets"].get(params.get("preset"))
        if preset is None:
            continue
        reads = preset["overlap_reads_per_contact"]
        new = keyed_id(with_todays_stride({**params, **BYTE_HASHED_TEMPLATES[params["scene_sha256"]],
                                           **ADDED_SINCE_BYTES, "scene_sha256": CARRIED_TO}, reads))
        if folder.name == new:  # carried already (its record keeps the old template's parameters)
            continue
        if not _named_by(folder, params, reads):
            report["left"].append((folder.name, f"the parameters in {source} are not this folder's"))
            continue
        if _rename_case(folder, new, dry_run, report):
            report["renamed"].append((folder.name, new))
    return report
