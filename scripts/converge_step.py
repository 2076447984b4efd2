"""Snakemake entry (checkpoint): after n cases of `snakemake converge`, stop (map criteria met, or
the case / CPU budget spent) or choose the next batch. The logic is spreadmap.loop.stepper;
the model is the map's model (the `surrogate:` config), the cost of a case the scene's plan."""
import json

import pandas as pd

from spreadmap.design import Design
from spreadmap.files import write_text_atomically
from spreadmap.logs import log_to
from spreadmap.loop.cost import PlannedCost
from spreadmap.loop.model import make_map_fit
from spreadmap.loop.stepper import step
from spreadmap.noise_law.apply import case_noise
from spreadmap.records import read_json_object, read_metrics

log_to(snakemake)  # noqa: F821

sm = snakemake  # noqa: F821
p = sm.params
design = Design.from_ranges(sm.params.ranges)  # the design space (config ranges), built once
n = int(sm.wildcards.n)
rows = []
for path in sm.input.metrics:
    rows.append(read_metrics(path))  # a damaged record is moved aside and re-made, never read
# run order: the previous step's cases first; noise SDs of MFR and PD from the fitted law (config
# noise_model), the others scaled by region (config noise_calibration)
table = case_noise(pd.DataFrame(rows), p.noise_model, p.noise_calibration, p.counting_c)
previous = None
if "previous" in sm.input.keys():
    previous = read_json_object(sm.input.previous, "loop step record", ("n", "stop"))
record = step(table, n, p.converge, previous, fit=make_map_fit(p.surrogate, final=True), ranges=design,
              maps_cfg=p.maps, lds_seed=p.lds_seed, tolerance=p.tolerance, floors=p.floors,
              cost=PlannedCost.from_config(p.scene_config))
record["noise_calibration"] = list(p.noise_calibration)
record["noise_model"] = p.noise_model
write_text_atomically(sm.output.step, json.dumps(record, indent=1, default=str))
print(record["summary"])
