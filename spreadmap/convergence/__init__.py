"""Is the sample big enough?  Two answers, kept apart.

* ``study_rule`` -- the reference study's rule (five statistics of MFR and PD change by less than
  0.5 % between partitions), computed exactly as the study ran it and reported as the study's
  row.  Its names are re-exported here (``spreadmap.convergence.convergence_table`` etc.).
* ``map_criteria`` -- the workflow's own stopping rule, about the map: cross-validated model
  error against the noise, the maps' change between batches against the noise, and bootstrap
  confidence intervals of the partition statistics.
* ``model`` -- the small interface those criteria need from a fitted model (and a Gaussian
  process behind it), ``active`` -- where the next batch of cases goes,
  ``noisy_study`` -- the sampling-design study with noise, ``sampling_study`` -- the study's
  rule on noise-free test functions, ``plots`` -- their figures.
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
