rule convergence:
    """Five statistics of MFR and PD per partition (LDS and lattice) and case by case (LDS)."""
    input:
        tables=[f"results/tables/{name}.csv" for name in ("lds", "lattice") if name in SWEEPS],
    output:
        summary="results/convergence/summary.json",
        partitions="results/convergence/partitions.csv",
        running="results/convergence/lds_case_by_case.csv",
        distributions=report("results/convergence/distributions.png", caption="captions/distributions.rst",
                             category="Convergence"),
        statistics=report("results/convergence/statistics.png", caption="captions/statistics.rst",
                          category="Convergence"),
    params:
        partitions=SWEEPS["lds"]["partitions"] if "lds" in SWEEPS else [],  # no LDS sweep: no partitions
        tolerance=STUDY_RULE["tolerance"],
        floors=STUDY_RULE["floors"],
        window=STUDY_RULE["window"],
        floor=FLOOR,
    log:
        "logs/convergence.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/study_rule.py"


rule sampling_study:
    """How many cases LDS, lattice and random sampling need to converge, without DEM: on smooth
    test functions and on the trained surrogate of the real results."""
    input:
        model="results/surrogate/model.joblib",
    output:
        table="results/convergence/sampling_study.csv",
        summary="results/convergence/sampling_study_summary.csv",
        figure=report("results/convergence/sampling_study.png", caption="captions/sampling_study.rst",
                      category="Convergence"),
    params:
        study=STUDY_RULE["sampling_study"],
        tolerance=STUDY_RULE["tolerance"],
        floors=STUDY_RULE["floors"],
        ranges=RANGES,
    log:
        "logs/sampling_study.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/sampling_study.py"
