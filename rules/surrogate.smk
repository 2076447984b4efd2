rule surrogate:
    """The noise-aware surrogate (GP and bootstrap MLP ensemble, validated by repeated k-fold against
    the noise; the map model trained on every usable case) and the study's MLP protocol beside it."""
    input:
        table=TRAINING_TABLE,
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
        surrogate=config["surrogate"],
        ranges=RANGES,
        noise_calibration=config["noise_calibration"],
        noise_model=config.get("noise_model"),  # optional: absent, the stated counting-law SDs
        counting_c=config["metrics"]["counting_noise_c"],
        floor=FLOOR,
        correction=config["fidelity_correction"] if _CORRECTION else None,  # None where it does not apply
    log:
        "logs/surrogate.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/surrogate.py"


rule predict:
    """Surrogate predictions for the chosen points of config `points`: per target the mean, the
    model's SD and the SD a new DEM run would show."""
    input:
        model="results/surrogate/model.joblib",
    output:
        "results/surrogate/predictions.csv",
    params:
        points=[{"name": p["name"], **p["point"]} for p in _points],
    log:
        "logs/predict.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/predict.py"
