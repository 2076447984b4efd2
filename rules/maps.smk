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
