rule results_table:
    """One results table per set of cases (a sweep, the named cases, chosen points)."""
    input:
        metrics=lambda wc: case_files(wc.set, "metrics.json"),
        benchmarks=lambda wc: case_files(wc.set, "benchmark.tsv"),
    output:
        table="results/tables/{set}.csv",
    params:
        labels=lambda wc: [label for _, label in SETS.get(wc.set, [])],
    log:
        "logs/table/{set}.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/results_table.py"
