"""spreadmap: the analysis side of the spreadmap workflow.

Everything computed outside YADE lives here (scene derivation, metrics, sampling, convergence,
surrogate, maps) so that it can be unit-tested without a DEM run.  Nothing in this package is
imported by the scripts that run inside YADE (yade_scripts/), which use Debian's own Python.
"""
