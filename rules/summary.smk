rule run_summary:
    """What is done, failed and flagged, with reasons, per set of cases: the main job's (the
    converge run and the chosen points)."""
    input:
        tables=lambda wc: main_tables(),
    output:
        json="results/summary.json",
        text="results/summary.txt",
    params:
        regime=config["regime"],
        floor=FLOOR,
    log:
        "logs/summary.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/run_summary.py"


rule sweeps_summary:
    """The same for the fixed sets (`snakemake sweeps`): the study's sweeps and the chosen points."""
    input:
        tables=[f"results/tables/{name}.csv" for name in SWEEPS] + (["results/tables/points.csv"] if "points" in SETS else []),
    output:
        json="results/sweeps_summary.json",
        text="results/sweeps_summary.txt",
    params:
        regime=config["regime"],
        floor=FLOOR,
    log:
        "logs/sweeps_summary.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/run_summary.py"
