"""The published study's convergence rule, kept apart from the workflow's own stopping rule
(``spreadmap.loop.map_criteria``).

* ``rule`` -- the reference study's rule (five statistics of MFR and PD change by less than
  0.5 % between partitions), computed exactly as the study ran it and reported as the study's
  row.  Its names are re-exported here (``spreadmap.study_rule.convergence_table`` etc.).
* ``rule_plots`` -- its figures: the distributions per partition and the statistics against N.
"""
from .rule import (  # noqa: F401
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
