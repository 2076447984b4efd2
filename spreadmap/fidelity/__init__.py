"""The fidelity study (config ``fidelity:``, rules/fidelity.smk): how far each cheaper preset's MFR
and PD are from the reference preset's, against what they cost.

* ``plan`` -- which cases it runs: every reference point at every preset and packing seed, and
  the one-knob-at-a-time sweeps (each knob value a preset of its own).
* ``study`` -- its numbers: each preset's and knob value's error, seed-to-seed noise and cost.
* ``plots`` -- its figures: error against cost per preset, and the knob sweeps.
"""
