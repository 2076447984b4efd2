"""Experiments without DEM: the loop's code and the study's rule against known truths.

* ``replay`` -- the loop's step code against a known truth with the measured noise and cost
  (``replay_plots``: its figure).
* ``sampling_study`` -- the study's rule on noise-free test functions; ``noisy_study`` -- the
  older sampling-design study with noise; ``cost_study`` -- the map per CPU hour.
* ``experiment_plots`` -- the figures of the three sampling studies.
* ``arms`` -- DEM studies in arms (benchmarks); ``paired`` -- an arm against a base arm, case by
  case (tools/paired_arms.py, spreadlab.readme_numbers).

Run by benchmarks/replay.py, benchmarks/noisy_study.py and benchmarks/cost_study.py; the
sampling study by the workflow (scripts/sampling_study.py).
"""
