"""Is the sample big enough?  Two answers, kept apart.

* ``study_rule`` -- the reference study's rule (five statistics of MFR and PD change by less than
  0.5 % between partitions), computed exactly as the study ran it and reported as the study's
  row.  Its names are re-exported here (``spreadmap.convergence.convergence_table`` etc.).
* ``map_criteria`` -- the workflow's own stopping rule, about the map: the map's own error against
  a tolerance per target (cross-validation net of the noise, and the posterior over the map
  grids), with cross-validated error against the noise, the maps' change between batches and
  bootstrap confidence intervals of the partition statistics reported beside it.
* ``model`` -- the map's model (the surrogate that draws the maps) behind the small interface
  those criteria need, ``active`` -- where the next batch of cases goes, ``cost`` -- what a case
  will cost, from the spheres and steps its scene plans, ``stepper`` -- one step of the loop.
* ``replay`` -- the loop's step code against a known truth with the measured noise and cost, no
  DEM (``replay_plots``: its figure); ``noisy_study`` -- the older sampling-design study with
  noise, ``sampling_study`` -- the study's rule on noise-free test functions, ``plots`` -- their
  figures.
"""
from .study_rule import (  # noqa: F401
    DEFAULT_FLOORS,
    DEFAULT_TARGETS,
    DEFAULT_TOLERANCE,
    NOT_CONVERGED,
    STATISTICS,
    TINY,
    batches_until_converged,
    convergence_table,
    criterion_holds,
    first_converged,
    first_stable_n,
    partition_statistics,
    running_statistics,
    summary,
)
