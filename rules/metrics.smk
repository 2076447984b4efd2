rule case_metrics:
    """MFR, PD (exact volumes), layer quality, the case's noise estimate, regime and stability flags of one case."""
    input:
        unpack(case_raw_input),
    output:
        metrics="results/cases/{case}/metrics.json",
    params:
        regime=config["regime"],
        stability=config["stability"],
        metrics=config["metrics"],
    log:
        "results/cases/{case}/metrics.log",
    localrule: True
    priority: QUICK_FIRST
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/case_metrics.py"
