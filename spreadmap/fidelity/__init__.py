"""The fidelity study (config ``fidelity:``, rules/fidelity.smk): how far each cheaper preset's MFR
and PD are from the reference preset's, against what they cost.

* ``plan`` -- which cases it runs: every reference point at every preset and packing seed, and
  the one-knob-at-a-time sweeps (each knob value a preset of its own).
* ``study`` -- its numbers: each preset's and knob value's error, seed-to-seed noise and cost.
* ``paired_factor`` -- the factor from a preset to the reference, measured on paired cases
  (config ``fidelity_correction``; the maps apply it: ``surrogate.correction``).
* ``fidelity_plots`` -- its figures: error against cost per preset, the knob sweeps, the factor.
"""
