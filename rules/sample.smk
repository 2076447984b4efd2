rule sample_lds:
    """The LDS sample table (scrambled Halton, seeded) as run by the sweep: for the record."""
    output:
        samples="results/samples/lds.csv",
    params:
        n=lambda wc: lds_size(),
        seed=SWEEPS["lds"]["seed"] if "lds" in SWEEPS else None,  # no LDS sweep: the rule is not asked for
        ranges=RANGES,
    log:
        "logs/samples/lds.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/sample_table.py"


rule sample_lattice:
    """The lattice sample table, k^4 points for each k of the sweep."""
    output:
        samples="results/samples/lattice.csv",
    params:
        k=SWEEPS["lattice"]["k"] if "lattice" in SWEEPS else [],  # no lattice sweep: the rule is not asked for
        ranges=RANGES,
    log:
        "logs/samples/lattice.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/sample_table.py"
