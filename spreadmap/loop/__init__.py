"""The main job's adaptive loop (``snakemake converge``): fit the map, check whether it is good
enough, and if not choose the next batch of cases.

* ``map_criteria`` -- the workflow's own stopping rule, about the map: the map's own error against
  a tolerance per target (cross-validation net of the noise, and the posterior over the map
  grids), with cross-validated error against the noise, the maps' change between batches and
  bootstrap confidence intervals of the partition statistics reported beside it.
* ``model`` -- the map's model (the surrogate that draws the maps) behind the small interface
  those criteria need, ``active`` -- where the next batch of cases goes, ``cost`` -- what a case
  will cost, from the spheres and steps its scene plans, ``stepper`` -- one step of the loop.
* ``loop_plot`` -- the loop's figure: each criterion at every batch.

The published study's rule is reported beside the loop's criteria; it lives in
``spreadmap.study_rule``.
"""
