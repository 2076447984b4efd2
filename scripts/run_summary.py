"""Snakemake entry: the run summary (JSON and text) from the results tables."""
import json
from pathlib import Path

from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.records import read_table
from spreadmap.run_report import run_summary, summary_text

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
# a set is named by its table: results/tables/<set>.csv, or results/<set>/table.csv (the converge run)
tables = {(Path(p).parent.name if Path(p).stem == "table" else Path(p).stem): read_table(p) for p in sm.input.tables}
summary = run_summary(tables, sm.params.regime, sm.params.floor)
write_text_atomically(sm.output.json, json.dumps(summary, indent=1))
text = summary_text(summary)
write_text_atomically(sm.output.text, text)
print(text)
