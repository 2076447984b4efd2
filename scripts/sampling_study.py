"""Snakemake entry: the DEM-free sampling-design study (LDS vs lattice vs random)."""
from spreadlab.experiments import sampling_study
from spreadlab.experiments.experiment_plots import plot_sampling_study
from spreadmap.design import Design
from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.surrogate import load_model

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
p = sm.params
design = Design.from_ranges(sm.params.ranges)  # the design space (config ranges), built once
model = load_model(sm.input.model)
result = sampling_study.study(predictor=model, ranges=design, seeds=p.study["seeds"],
                              k_max=p.study["k_max"], tolerance=p.tolerance, floors=p.floors)
write_text_atomically(sm.output.table, result.table.to_csv(index=False))
write_text_atomically(sm.output.summary, result.summary.to_csv(index=False))
plot_sampling_study(result.table, sm.output.figure[: -len(".png")], result.summary)
print(result.summary.to_string())
print(result.ratios.to_string())
