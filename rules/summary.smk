rule run_summary:
    """What is done, failed and flagged, with reasons, per set of cases."""
    input:
        tables=lambda wc: set_tables(),
    output:
        json="results/summary.json",
        text="results/summary.txt",
    params:
        regime=config["regime"],
    log:
        "logs/summary.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/run_summary.py"
