rule surrogate:
    """MLP surrogates of MFR and PD on the LDS sweep (hidden-neuron sweep, 3 seeds, 80/20 split
    shared by all partitions, CV, learning curve, GP baseline, ensemble uncertainty)."""
    input:
        table="results/tables/lds.csv",
    output:
        model="results/surrogate/model.joblib",
        metadata="results/surrogate/model.json",
        metrics="results/surrogate/surrogate_metrics.csv",
        parity=report("results/surrogate/surrogate_parity.png", caption="captions/parity.rst", category="Surrogate"),
        r2=report("results/surrogate/surrogate_r2_vs_neurons.png", caption="captions/r2_vs_neurons.rst",
                  category="Surrogate"),
        learning=report("results/surrogate/surrogate_learning_curve.png", caption="captions/learning_curve.rst",
                        category="Surrogate"),
    params:
        surrogate=config.get("surrogate", {}),
    log:
        "logs/surrogate.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/surrogate.py"


rule predict:
    """Surrogate predictions (with uncertainty) for the chosen points of config `points`."""
    input:
        model="results/surrogate/model.joblib",
    output:
        "results/surrogate/predictions.csv",
    params:
        points=[p["point"] for p in _points],
    log:
        "logs/predict.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/predict.py"
