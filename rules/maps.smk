MAPS = config["maps"]
MAP_FIGURES = ["machine_map", "powder_band_map", "powder_cluster_map", "parallel_coordinates",
               "regime_overlay", "sensitivity_ranking"]


rule maps:
    """Processing design maps from the surrogate, the DEM sample in parallel coordinates, the
    regime overlay, and the parameter ranking (band widths and Sobol indices)."""
    input:
        model="results/surrogate/model.joblib",
        table=TRAINING_TABLE,
    output:
        **{name: report(f"results/maps/{name}.png", caption=f"captions/{name}.rst", category="Maps")
           for name in MAP_FIGURES},
        ranking="results/maps/sensitivity_ranking_table.csv",
        y_choice="results/maps/machine_y_choice.csv",
        regime_plane="results/maps/regime_overlay_plane.csv",  # the regime figure's (d, h) plane; its CSV: the cases
    params:
        maps=MAPS,
        floor=MAP_BASIS,
        regime=config["regime"],
        ranges=RANGES,
        noise_calibration=config["noise_calibration"],
        noise_model=config.get("noise_model"),  # optional: absent, the stated counting-law SDs
        counting_c=config["metrics"]["counting_noise_c"],
    log:
        "logs/maps.log",
    localrule: True
    priority: ANALYSES_FIRST
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/maps.py"


MLP_MAP_FIGURES = ["machine_map", "powder_band_map"]


rule maps_mlp:
    """The MLP ensemble's machine map and powder map (a) beside the map model's (same grids, same y),
    each labelled with the MLP's cross-validated RMSE over one run's noise SD per target drawn (and
    the GP's), from the validation table: what the study's model would have said."""
    input:
        model="results/surrogate/model_mlp.joblib",
        table=TRAINING_TABLE,
        validation=SURROGATE_VALIDATION,
    output:
        **{name: report(f"results/maps/{name}_mlp.png", caption=f"captions/{name}_mlp.rst", category="Maps")
           for name in MLP_MAP_FIGURES},
    params:
        maps=MAPS,
        floor=MAP_BASIS,
        ranges=RANGES,
        **_SURROGATE_NOISE,
    log:
        "logs/maps_mlp.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/maps_mlp.py"
