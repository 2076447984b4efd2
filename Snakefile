# spreadmap: DEM powder-spreading cases (YADE) -> MFR/PD table -> analyses -> design maps.
#   snakemake --cores 2          the main job on config.yaml (profile profiles/default): LDS cases, then
#                                batches until the map criteria hold or the budget is spent, maps
#   snakemake -n                 what would run
#   snakemake points             your chosen points only (config `points:`)
#   snakemake sweeps             the study's protocol: fixed LDS and lattice sweeps, their statistics
#   snakemake converge           the main job's cases and stopping decision only
#   snakemake sampling           the DEM-free sampling-design study (on the main job's surrogate too)
#   snakemake decisions          recommended settings per powder (config `decisions:`) and the explorer page
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
include: "rules/study_rule.smk"
include: "rules/converge.smk"
include: "rules/surrogate.smk"
include: "rules/maps.smk"
include: "rules/decisions.smk"
include: "rules/pictures.smk"
include: "rules/fidelity.smk"


MAIN_JOB = [  # what the main job makes (rule all), before its timeline
    "results/converge/stopped.json",
    "results/summary.json",
    "results/surrogate/model.joblib",
    *rules.surrogate_validation.output,  # the surrogate's validation: beside the maps, which do not wait for it
    *prediction_targets(),
    "results/maps/sensitivity_ranking_table.csv",
    *rules.maps_mlp.output,  # the MLP's maps beside the map model's, labelled with its validation
    *rules.decisions.input,
    *expand("results/pictures/{name}.png", name=PICTURES["cases"]),
    *expand("results/vtk/{name}", name=PICTURES["vtk"]),
]


rule all:
    """The main job: a map you can trust within a budget. LDS cases, then batches until the map
    criteria hold or the budget is spent (rules/converge.smk); the surrogate and the maps on that
    run's table; predictions at the chosen points; the recommended settings and the explorer page
    (rules/decisions.smk); pictures of the named cases; last, the run's timeline."""
    default_target: True
    input:
        MAIN_JOB,
        "results/converge/timeline.png",


rule timeline:
    """Where the main job's wall time went: its jobs on the cores they ran on, from this run's
    Snakemake log, the core time of the DEM cases, the loop's steps and the analyses, and the idle
    time (spreadmap.loop.timeline). A run resumed after an interruption shows its last part."""
    input:
        MAIN_JOB,
    output:
        figure=report("results/converge/timeline.png", caption="rules/captions/timeline.rst", category="Convergence"),
        summary="results/converge/timeline.json",
    params:
        cores=run_cores,
        floor=FLOOR,
    log:
        "logs/timeline.log",
    localrule: True
    conda:
        "envs/analysis.yaml"
    script:
        "scripts/timeline.py"


rule sweeps:
    """The study's protocol: the fixed LDS and lattice sweeps and the five statistics per partition
    (the study's convergence rule); the summary covers them and the chosen points."""
    input:
        [f"results/samples/{name}.csv" for name in SWEEPS],
        [f"results/tables/{name}.csv" for name in SWEEPS],
        "results/sweeps_summary.json",
        "results/convergence/summary.json",


rule sampling:
    """The DEM-free sampling-design study (LDS, lattice, random; the study's rule) on smooth test
    functions and on the main job's surrogate."""
    input:
        "results/convergence/sampling_study.csv",


rule points:
    input:
        "results/tables/points.csv",
