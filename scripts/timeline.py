"""Snakemake entry: the main job's timeline from this run's own Snakemake log (the newest of
.snakemake/log): its jobs on the cores, the core time by kind and the idle time."""
import json
from pathlib import Path

from spreadmap.files import write_text_atomically
from spreadmap.loop.timeline import core_time, parse_log, place_on_cores
from spreadmap.loop.timeline_plot import draw_timeline

sm = snakemake  # noqa: F821
logs = sorted(Path(".snakemake/log").glob("*.snakemake.log"), key=lambda p: p.stat().st_mtime)
if not logs:
    raise SystemExit("timeline: no Snakemake log in .snakemake/log")
placed = place_on_cores(parse_log(logs[-1].read_text()))
summary = core_time(placed, sm.params.cores)  # None (a cluster run): the most jobs at once
stem = Path(sm.output.figure).with_suffix("")
draw_timeline(placed, summary, stem, "the main job's timeline", floor=sm.params.floor)
write_text_atomically(Path(sm.output.summary), json.dumps({**summary, "log": logs[-1].name}, indent=1) + "\n")
print(json.dumps(summary))
