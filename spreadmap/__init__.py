"""spreadmap: the analysis side of the spreadmap workflow.

Everything computed outside YADE lives here (scene derivation, metrics, sampling, convergence,
surrogate, maps) so that it can be unit-tested without a DEM run.  Nothing in this package is
imported by the scripts that run inside YADE (yade_scripts/), which use Debian's own Python.

Rooms (sub-packages), one job each:

* ``case`` -- one DEM case, from design point to files: its identity (content key, case id), its
  scene, the rendered YADE script, the launcher, the floor, its pictures and VTK files.
* ``loop`` -- the main job's adaptive loop (``snakemake converge``, rules/converge.smk): its stop
  rule about the map, the map's model, where the next batch goes, what a case costs, one step.
* ``study_rule`` -- the published study's convergence rule (rules/study_rule.smk), as it ran.
* ``fidelity`` -- the fidelity study: the cases it plans, its numbers, its figures.
* ``surrogate`` -- the noise-aware surrogate, its validation, the saved model and prediction.
* ``maps`` -- the design maps drawn from the surrogate; ``decisions`` -- from the maps to the
  settings to run a powder at; ``sensitivity`` -- the parameters ranked by influence.
* ``metrics`` -- one case's raw YADE output reduced to its row of the results table (with the exact
  sphere/box volumes, ``metrics.geometry``).
* ``noise_law`` -- the fitted noise law applied to a results table.

The lab (experiments, the published study, the noise law's fitting, comparisons, the README's
numbers) is the package beside this one, ``spreadlab``: it imports this package, never the reverse.

Where each concept is held (one module each):

* case identity, content keys: ``case.identity`` (case_scene, case_id, content_key); a case's
  scene: ``case.scene``; its script: ``case.render``; its run: ``case.launcher``; a failed one
  retried: ``case.retry``; its floor: ``case.substrate``
* the cases the sweeps plan (the workflow's registry): ``sweeps`` (planned_cases, loop_labels)
* design space: ``design.Design``, built once from the config (``Design.from_config``): names,
  ranges, to / from the unit cube, axes; h/d (``design.h_over_d``); every ``ranges`` argument takes it;
  the axes themselves (name, symbol, label, range, unit, nominal): ``design.PARAMETERS``, their one home
* the 2-D slices (which two axes vary, on what grid, the fixed ones from config ``maps:`` /
  ``decisions:`` or at their nominal value): ``slices`` (read by the maps, the decisions, the explorer
  and the loop's criteria)
* targets (name, labels, unit, SD and count columns, kind): ``targets`` (``REGISTRY``; read by
  metrics, surrogate, maps, decisions and the explorer)
* results table, usable cases: ``table`` (build_table; ``usable`` = finished, not flagged and finite in
  the columns asked, the one rule every reader calls; ``usable_cases`` its rows); the noise SDs
  every analysis weighs cases by: ``noise_law.apply.case_noise``
* partitions (the LDS prefix ``index < n``): ``table.partition``; the study
  rule's statistics per partition: ``study_rule.rule``
* atomic writing: ``files`` (write_text_atomically, atomic_path); reading the workflow's files
  without taking a damaged one for data: ``records``
* config defaults: ``schema`` (schemas/config.schema.yaml, the one place a default is stated;
  ``schema.checked``: one section, or an object inside one, checked alone, defaults filled); loading a whole config:
  ``config`` (load: the schema's defaults filled, then the cross-key checks; the sections the later
  stages own are checked by their owners, wired in below)
* noise model: ``noise_law.apply`` (config ``noise_model``; fitted by spreadlab.noise_law); a case's own estimate:
  ``metrics.noise``; a new run's SD at a point: ``surrogate.noise_sd``
* the loop: ``loop.stepper`` (one step; its criteria ``loop.map_criteria``)
* the study rule: ``study_rule.rule``
* fidelity: ``fidelity`` (``plan``, ``study``, ``fidelity_plots``)
* surrogate: ``surrogate`` (``fitting``, ``prediction``); maps: ``maps``; decisions:
  ``decisions``; metrics: ``metrics`` (``case.case_metrics``); sensitivity: ``sensitivity``
"""
from .config import SECTION_CHECKS
from .decisions.config_section import problems as _decisions_problems
from .fidelity.plan import check as _fidelity_problems
from .surrogate.settings import problems as _surrogate_problems

# Each later stage checks its own config section; config, the ground floor, imports none of them
# (issue 65): the package hands their checks to it once, here, so every spreadmap.config.validate
# refuses every section's problem, in this order.
SECTION_CHECKS[:] = [_surrogate_problems, _decisions_problems, _fidelity_problems]
