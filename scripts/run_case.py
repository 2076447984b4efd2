"""Snakemake entry: run one case with Debian's YADE (clean environment, outer timeout).

A run that ends with a raw result (ok, or blown up and stopped by the watchdog: deterministic, so
not worth retrying) succeeds. A run that produced nothing because of a crash or a timeout fails
so that Snakemake retries it; a refusal or a failed check of the YADE script (deterministic) and
the last attempt of a crash write a failure record with the reason and the log's tail instead,
so the case shows up in the table with its reason and never blocks the others.
A finished simulation of the same parameters (simulated.json, beside the output) is re-used."""
import sys

from spreadmap.case.launcher import failure_record, retry_wanted, simulate, write_json_atomically

sm = snakemake  # noqa: F821
params = sm.params.scene.params  # spreadmap.case.identity.SceneParams
result = simulate(params, sm.input.script, sm.output.raw, sm.log[0])
print(f"{params['case_id']}: {result['outcome']} after {result['wall_time']:.1f} s {result['reason']}")
if result["outcome"] not in ("ok", "blown"):
    if retry_wanted(result, sm.resources.attempt, sm.params.retries):
        sys.exit(f"{params['case_id']}: {result['reason']} (attempt {sm.resources.attempt}; will be retried)")
    write_json_atomically(sm.output.raw, failure_record(params, result, sm.log[0]))
