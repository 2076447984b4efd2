"""Send a Snakemake script's output (stdout and stderr) to the rule's log file as well, and turn a
damaged input file into a re-make (spreadmap.records.remake_when_corrupt)."""
from __future__ import annotations

import sys


class _Tee:
    def __init__(self, *streams):
        self.streams = streams

    def write(self, text):
        for s in self.streams:
            s.write(text)
            s.flush()
        return len(text)

    def flush(self):
        for s in self.streams:
            s.flush()


def log_to(smk) -> None:
    """Tee stdout and stderr into smk.log[0] (if the rule declares a log).

    A damaged file the job reads (spreadmap.records.CorruptFileError) is moved aside and the job
    ends with one line, so that the next run re-makes it (``spreadmap.records.remake_when_corrupt``
    is installed as the job's ``sys.excepthook``).

    Parameters
    ----------
    smk : snakemake.script.Snakemake
        The ``snakemake`` object of a rule's script; only ``smk.log`` is read. Without a log
        file, stdout and stderr are left as they are.
    """
    from .records import remake_when_corrupt

    remake_when_corrupt()
    if len(smk.log):
        log = open(smk.log[0], "w", buffering=1)
        sys.stdout = _Tee(sys.__stdout__, log)
        sys.stderr = _Tee(sys.__stderr__, log)
