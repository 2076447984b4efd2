rule run_case:
    """Run one case with Debian's YADE (single thread, clean environment, outer timeout)."""
    input:
        script="results/cases/{case}/case.py",
    output:
        raw="results/cases/{case}/raw.json",
    log:
        "results/cases/{case}/run.log",
    benchmark:
        "results/cases/{case}/benchmark.tsv"
    params:
        scene=lambda wc: SceneParams(CASES[wc.case]),  # not a re-run trigger: the case id holds the scene
        retries=RETRIES,
    retries: RETRIES
    priority: case_cost_priority
    threads: 1
    resources:
        attempt=lambda wc, attempt: attempt,
        runtime=lambda wc: max(5, int(CASES[wc.case]["timeout_s"] / 60) + 5),
        mem_mb=1000,
    conda:
        "../envs/yade.yaml"
    script:
        "../scripts/run_case.py"
