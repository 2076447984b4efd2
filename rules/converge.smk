# `snakemake converge`: grow the LDS sweep batch by batch until the convergence criterion holds
# for k_consecutive batches in a row, or the case budget is reached. Each step is a checkpoint:
# the dry run shows the next batch of cases, and every finished case is re-used.


checkpoint converge_step:
    input:
        metrics=lambda wc: [f"results/cases/{cid}/metrics.json" for cid in lds_case_ids(int(wc.n))],
    output:
        step="results/converge/step_{n}.json",
    params:
        start=GROW.get("start", 32),
        batch=GROW.get("batch", 16),
        k_consecutive=GROW.get("k_consecutive", 3),
        budget=GROW.get("budget", 512),
        tolerance=CONV.get("tolerance", 0.005),
        floors=CONV.get("floors"),
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
    """Where the growing LDS sweep stopped, and why."""
    input:
        final_converge_step,
    output:
        "results/converge/stopped.json",
    log:
        "logs/converge/stopped.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    shell:
        "cp {input} {output} && cat {output} > {log}"
