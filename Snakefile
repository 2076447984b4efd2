# spreadmap: DEM powder-spreading cases (YADE) -> MFR/PD table -> analyses -> design maps.
#   snakemake --cores 2          the main job on config.yaml (profile profiles/default)
#   snakemake -n                 what would run
#   snakemake points             your chosen points only (config `points:`)
#   snakemake sweeps             the sweeps' results tables and the run summary
#   snakemake converge           grow the LDS sweep until its statistics converge (or the budget)
#   snakemake fidelity           each preset's error against `reference`, its noise and its cost
#   snakemake --report report.html   every figure with its caption, the tables and the summary
from snakemake.utils import min_version

min_version("9.0")


configfile: "config.yaml"


include: "rules/common.smk"
include: "rules/sample.smk"
include: "rules/render.smk"
include: "rules/simulate.smk"
include: "rules/metrics.smk"
include: "rules/table.smk"
include: "rules/summary.smk"
include: "rules/convergence.smk"
include: "rules/converge.smk"
include: "rules/surrogate.smk"
include: "rules/maps.smk"
include: "rules/pictures.smk"
include: "rules/fidelity.smk"


rule all:
    default_target: True
    input:
        [f"results/samples/{name}.csv" for name in SWEEPS],
        set_tables(),
        "results/summary.json",
        "results/convergence/summary.json",
        "results/convergence/sampling_study.csv",
        "results/surrogate/model.joblib",
        prediction_targets(),
        "results/maps/sensitivity_ranking_table.csv",
        expand("results/pictures/{name}.png", name=PICTURES.get("cases", [])),
        expand("results/vtk/{name}", name=PICTURES.get("vtk", [])),


rule sweeps:
    input:
        [f"results/tables/{name}.csv" for name in SWEEPS],
        "results/summary.json",


rule points:
    input:
        "results/tables/points.csv",
