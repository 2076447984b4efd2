_SURROGATE_NOISE = dict(  # the cases' noise SDs, the same for the map model and its validation
    noise_calibration=config["noise_calibration"],
    noise_model=config.get("noise_model"),  # optional: absent, the stated counting-law SDs
    counting_c=config["metrics"]["counting_noise_c"],
)
SURROGATE_VALIDATION = "results/surrogate/surrogate_metrics.csv"


rule surrogate:
    """The map model: the noise-aware surrogate (GP or bootstrap MLP ensemble, config `surrogate.model`)
    trained on every usable case, the fidelity correction attached where it applies. What the maps,
    decisions, explorer and predictions read; its validation is rule surrogate_validation's, which
    they do not wait for (with `model: best` the validation chooses the model, so this rule waits)."""
    input:
        table=TRAINING_TABLE,
        **({"validation": SURROGATE_VALIDATION} if config["surrogate"]["model"] == "best" else {}),
    output:
        model="results/surrogate/model.joblib",
        metadata="results/surrogate/model.json",
    params:
        surrogate=config["surrogate"],
        ranges=RANGES,
        **_SURROGATE_NOISE,
        correction=config["fidelity_correction"] if _CORRECTION else None,  # None where it does not apply
    log:
        "logs/surrogate.log",
    localrule: True
    priority: ANALYSES_FIRST
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/surrogate.py"


rule surrogate_mlp:
    """The bootstrap MLP ensemble trained on every usable case for every target, whatever
    `surrogate.model` says (scripts/surrogate.py with `model_kind`): what rule maps_mlp draws beside
    the map model's maps. It waits for nothing but the table, and on two cores runs beside the map
    model and what reads it (priority just below theirs), before the validation takes both cores."""
    input:
        table=TRAINING_TABLE,
    output:
        model="results/surrogate/model_mlp.joblib",
        metadata="results/surrogate/model_mlp.json",
    params:
        surrogate=config["surrogate"],
        model_kind="mlp",
        ranges=RANGES,
        **_SURROGATE_NOISE,
        correction=config["fidelity_correction"] if _CORRECTION else None,  # as the map model's
    log:
        "logs/surrogate_mlp.log",
    localrule: True
    priority: ANALYSES_FIRST - 1
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/surrogate.py"


rule surrogate_validation:
    """The surrogate's validation against the noise on cases it never saw (repeated k-fold of the GP
    and the bootstrap MLP ensemble), the study's MLP protocol beside it and the learning curve: the
    tables and figures. The main job asks for it; nothing of the maps depends on it."""
    input:
        table=TRAINING_TABLE,
    output:
        metrics=SURROGATE_VALIDATION,
        study_runs="results/surrogate/surrogate_study_runs.csv",
        parity=report("results/surrogate/surrogate_parity.png", caption="captions/parity.rst", category="Surrogate"),
        r2=report("results/surrogate/surrogate_r2_vs_neurons.png", caption="captions/r2_vs_neurons.rst",
                  category="Surrogate"),
        learning=report("results/surrogate/surrogate_learning_curve.png", caption="captions/learning_curve.rst",
                        category="Surrogate"),
    params:
        surrogate=config["surrogate"],
        **_SURROGATE_NOISE,
        floor=FLOOR,
    log:
        "logs/surrogate_validation.log",
    threads: 2  # the k-fold validations in parallel, one per target and model (fewer with --cores 1)
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/surrogate_validation.py"


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
    priority: ANALYSES_FIRST
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/predict.py"
