"""Snakemake entry: MFR, PD, layer quality, noise estimate, regime and diagnostics of one case from its raw YADE output."""
from spreadmap.case.launcher import write_json_atomically
from spreadmap.logs import log_to
from spreadmap.metrics import case_metrics
from spreadmap.records import read_raw

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
if "raw" not in sm.input.keys():
    raise SystemExit(f"spreadmap: case {sm.wildcards.case} was restored from a published table (restored.json) "
                     "and its raw YADE record is not here; delete its folder under results/cases to re-run it")
raw = read_raw(sm.input.raw)  # a damaged record is moved aside and re-made, never read
write_json_atomically(sm.output.metrics, case_metrics(raw, sm.params.regime, sm.params.stability, sm.params.metrics))
