"""Snakemake entry: design maps, parallel coordinates, regime overlay and parameter ranking."""
from pathlib import Path

import pandas as pd

from spreadmap import maps, sensitivity
from spreadmap.surrogate import load_model
from spreadmap.logs import log_to

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
p = sm.params
out = Path(sm.output.ranking).parent
model = load_model(sm.input.model)
cases = pd.read_csv(sm.input.table)
machine, powder = p.maps.get("machine", {}), p.maps.get("powder", {})
maps.machine_map(model, out / "machine_map", ranges=p.ranges, **machine)
maps.powder_band_map(model, out / "powder_band_map", ranges=p.ranges, **powder)
maps.powder_cluster_map(model, out / "powder_cluster_map", ranges=p.ranges, **powder)
maps.parallel_coordinates(cases, out / "parallel_coordinates", mfr_min=p.maps.get("best_mfr_min", 0.0), ranges=p.ranges)
maps.regime_overlay(cases, model, out / "regime_overlay", jam_mfr_max=p.regime["jam_mfr_max"],
                    short_feed_pd_min=p.regime["short_feed_pd_min"])
ranking = sensitivity.sensitivity(model, n=p.maps.get("sobol_n", 1024), ranges=p.ranges)
ranking.to_csv(sm.output.ranking, index=False)
sensitivity.plot_ranking(ranking, out / "sensitivity_ranking")
print(ranking.to_string())
