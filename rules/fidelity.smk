# The fidelity study: every reference point at every preset and seed, and the knob sweeps
# (config `fidelity:`). `snakemake fidelity` runs it; nothing of the main job depends on it.
# (FIDELITY, KNOBS and fidelity_outputs: rules/common.smk)


rule fidelity_tables:
    """The study's two results tables only (every case simulated), without the analysis."""
    input:
        [f"results/tables/{name}.csv" for name in FIDELITY_SETS if name in SETS],


rule fidelity_analysis:
    """Each preset's error of MFR and PD against the reference, seed spread and cost; the knob
    sweeps; the goal checks; the Pareto and knob figures."""
    input:
        presets="results/tables/fidelity.csv",
        **({"knobs": "results/tables/knobs.csv"} if KNOBS else {}),
    output:
        per_point="results/fidelity/per_point.csv",
        presets="results/fidelity/presets.csv",
        knobs="results/fidelity/knobs.csv",
        summary="results/fidelity/summary.json",
        markdown="results/fidelity/summary.md",
        pareto=report("results/fidelity/pareto.png", caption="captions/fidelity_pareto.rst", category="Fidelity"),
        **({"knobs_figure": report("results/fidelity/knob_sweeps.png", caption="captions/fidelity_knobs.rst",
                                   category="Fidelity")} if KNOBS else {}),
    params:  # FIDELITY is {} without a `fidelity:` section (fidelity_outputs then refuses): .get, no defaults
        reference=FIDELITY.get("reference"),
        knob_preset=KNOBS.get("preset"),
        goal_presets=[p for p in FIDELITY.get("presets", []) if p != FIDELITY.get("reference")],
    log:
        "logs/fidelity.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/fidelity.py"


rule fidelity:
    """`snakemake fidelity`: the whole fidelity study."""
    input:
        fidelity_outputs,
