# The fidelity study: every reference point at every preset and seed, and the knob sweeps
# (config `fidelity:`). `snakemake fidelity` runs it; nothing of the main job depends on it.


rule fidelity_tables:
    """The study's two results tables only (every case simulated), without the analysis."""
    input:
        [f"results/tables/{name}.csv" for name in FIDELITY_SETS if name in SETS],
