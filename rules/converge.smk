# `snakemake converge`: a map you can trust within a budget. The run starts with `converge.start`
# LDS cases, then adds batches (chosen where the model is least sure about the maps, or the next
# LDS points) until the map criteria of `converge.stop_on` hold, or the case / CPU budget is spent.
# Each step is a checkpoint: `snakemake -n converge` shows the first stage (the LDS start), and the
# batch after a step is known only once that step has run. Every finished case is re-used.


checkpoint converge_step:
    input:
        unpack(converge_step_input),
    output:
        step="results/converge/step_{n}.json",
    params:
        converge=GROW,
        tolerance=STUDY_RULE["tolerance"],
        floors=STUDY_RULE["floors"],
        ranges=RANGES,
        maps=config["maps"],
        lds_seed=SWEEPS["lds"]["seed"] if "lds" in SWEEPS else None,  # no LDS sweep: no LDS sequence to start from
        noise_calibration=config["noise_calibration"],
        noise_model=config.get("noise_model"),  # optional: absent, the stated counting-law SDs
        counting_c=config["metrics"]["counting_noise_c"],
        surrogate=config["surrogate"],
        scene_config={k: config[k] for k in ("preset", "presets", "material", "scene", "metrics", "converge")},
    wildcard_constraints:
        n=r"\d+",
    log:
        "logs/converge/step_{n}.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/converge_step.py"


rule converge:
    """Where the run stopped and why: the criteria, the batch at which each held, the path; and
    the run's results table."""
    input:
        converge_final_step,
        "results/converge/table.csv",
    output:
        stopped="results/converge/stopped.json",
        summary="results/converge/summary.txt",
        path=report("results/converge/path.png", caption="captions/converge_path.rst", category="Convergence"),
    log:
        "logs/converge/stopped.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/converge_summary.py"


rule converge_table:
    """The results table of the converge run (every case, in run order, its batch): what a
    surrogate and the maps trained on the converged sample read."""
    input:
        step=converge_final_step,
        metrics=lambda wc: [f"results/cases/{cid}/metrics.json" for cid, _ in converge_final_cases()],
        benchmarks=lambda wc: [f"results/cases/{cid}/benchmark.tsv" for cid, _ in converge_final_cases()],
    output:
        table="results/converge/table.csv",
    params:
        labels=lambda wc: [label for _, label in converge_final_cases()],
    log:
        "logs/converge/table.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/results_table.py"
