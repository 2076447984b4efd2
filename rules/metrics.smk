rule case_metrics:
    """MFR, PD (exact sphere-box volumes), regime and stability flags of one case."""
    input:
        raw="results/cases/{case}/raw.json",
    output:
        metrics="results/cases/{case}/metrics.json",
    params:
        regime=config["regime"],
        stability=config["stability"],
    log:
        "results/cases/{case}/metrics.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/case_metrics.py"
