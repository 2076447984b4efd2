"""spreadlab: the lab beside the product (issue 65).

What serves experiments, the published study, the noise law's fitting, comparisons and the
README's numbers, and no part of the main job: the product (spreadmap, the workflow's scripts and
rules) never imports it; it imports the product. tools/import_graph.py lists which modules of
spreadmap the product reaches; tests/core/test_lab_boundary.py holds the boundary.

* ``experiments`` -- experiments without DEM: the loop's replay and the sampling studies
  (``sampling_study``: also the workflow's `snakemake sampling`), and DEM arms (``arms``, ``paired``).
* ``study`` -- the published study (docs/study): its cases, summary.md, restoring its cases,
  the published folders' checksums.
* ``noise_law`` -- the noise law fitted to seed repeats, checked held out, refitted, drawn; the
  counting law's constant c.
* ``paired_factor`` -- the preset-to-reference factor from paired cases (tools/fidelity_correction.py).
* ``recheck`` -- the loop's stop re-checked on a finished run (tools/recheck_stop.py).
* ``floors``, ``floors_plot`` -- the flat and rough floors compared (tools/compare_floors.py).
* ``window_start`` -- where a case's steady window starts (tools/window_start.py).
* ``heldout_points`` -- held-out points chosen and scored (tools/heldout.py).
* ``readme_numbers`` -- the README's numbers ledger (tools/readme_numbers.py).
* ``dryrun`` -- Snakemake's dry-run output read (the workflow's tests, benchmarks/main_job.py).
"""
