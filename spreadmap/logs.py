"""Send a Snakemake script's output (stdout and stderr) to the rule's log file as well."""
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
    """Tee stdout and stderr into smk.log[0] (if the rule declares a log)."""
    if len(smk.log):
        log = open(smk.log[0], "w", buffering=1)
        sys.stdout = _Tee(sys.__stdout__, log)
        sys.stderr = _Tee(sys.__stderr__, log)
