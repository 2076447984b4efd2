DECISIONS = config["decisions"]


rule decide:
    """Recommended settings per powder: the probability of meeting every bound over the machine's
    (h, v) grid from the surrogate's joint posterior draws; the fastest and the best-quality
    setting within the data (spreadmap.decisions)."""
    input:
        model="results/surrogate/model.joblib",
    output:
        table="results/decisions/recommendations.csv",
        figure=report("results/decisions/probability.png", caption="captions/decisions.rst", category="Decisions"),
    params:
        decisions=DECISIONS,
        support=MAPS["support"],
        floor=MAP_BASIS,
    log:
        "logs/decisions.log",
    localrule: True
    priority: ANALYSES_FIRST
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/decisions.py"


rule explorer:
    """The explorer page: one self-contained HTML file (plotly.js inlined) with sliders over f and
    d, the surrogate's mean and SD per target over (v, h), the data's reach, the cases run and the
    recommended region; its numbers as CSV beside it."""
    input:
        model="results/surrogate/model.joblib",
    output:
        html="results/decisions/explorer.html",
        csv="results/decisions/explorer.csv",
    params:
        decisions=DECISIONS,
        support=MAPS["support"],
        floor=MAP_BASIS,
    log:
        "logs/explorer.log",
    localrule: True
    priority: ANALYSES_FIRST
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/explorer.py"


rule decisions:
    """`snakemake decisions`: the recommendation table and figure, and the explorer page."""
    input:
        rules.decide.output,
        rules.explorer.output,
