"""Snakemake entry: where `snakemake converge` stopped and why, with the path it took."""
import json

from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.loop.loop_plot import plot_converge_path

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
with open(sm.input[0]) as fh:
    record = json.load(fh)
write_text_atomically(sm.output.stopped, json.dumps(record, indent=1, default=str))
lines = [record["summary"], "", "path (criterion / threshold at each batch; <= 1 holds):"]
for h in record["criteria"]["path"]:
    parts = [f"{c} {h[c]['value']:.2f}" for c in ("map_error", "cv_rmse", "map_change", "ci") if h.get(c)]
    lines.append(f"  {h['n']:5d} cases: " + ", ".join(parts))
stats = record.get("map_statistics") or {}
if stats:
    lines += ["", "the study's five statistics of the map over the design box (the model's mean map; 90 % over "
              "its posterior draws; noise-free, so SD and kurtosis lack the runs' noise):"]
    for target, per in stats.items():
        lines.append(f"  {target}: " + ", ".join(f"{s} {v['value']:.4g} [{v['low']:.4g}, {v['high']:.4g}]"
                                                 for s, v in per.items()))
write_text_atomically(sm.output.summary, "\n".join(lines) + "\n")
plot_converge_path(record, sm.output.path[: -len(".png")])
print("\n".join(lines))
