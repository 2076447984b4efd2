rule render_case:
    """One self-contained YADE script per case, its parameters embedded (re-runnable by hand)."""
    output:
        script="results/cases/{case}/case.py",
    params:
        scene=lambda wc: SceneParams(CASES[wc.case]),  # not a re-run trigger: the case id holds the scene
    log:
        "results/cases/{case}/render.log",
    localrule: True
    priority: QUICK_FIRST
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/render_case.py"
