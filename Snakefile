# spreadmap: DEM powder-spreading cases (YADE) -> MFR/PD table -> analyses -> design maps.
#   snakemake --cores 2          the main job on config.yaml (profile profiles/default)
#   snakemake -n                 what would run
#   snakemake cases              the named cases of config.yaml (`cases:`)
from snakemake.utils import min_version

min_version("9.0")


configfile: "config.yaml"


include: "rules/common.smk"
include: "rules/render.smk"
include: "rules/simulate.smk"
include: "rules/metrics.smk"
include: "rules/table.smk"


rule all:
    default_target: True
    input:
        "results/tables/cases.csv",


rule cases:
    input:
        "results/tables/cases.csv",
