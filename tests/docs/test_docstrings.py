"""The public API's docstrings are numpydoc and agree with the signatures (issue 34).

The public API is what the workflow's thin entry points (scripts/*.py, tools/*.py) import from the
package; in spreadmap/case, config, files, maps, study, experiments and surrogate/plots also what
other modules of the package, rules/*.smk and benchmarks/*.py import from them, and the names of a
module's ``__all__``. It is listed below by hand: a name that starts to be used so is added here
with its docstring. For each function, class (its constructor's arguments) and public method of a
class:

* a summary line;
* section headers that numpydoc knows (a header is a line underlined with dashes);
* a ``Parameters`` section when it takes arguments other than self/cls, whose entries
  (``name : type`` lines at the section's indentation, each followed by an indented description)
  are exactly the signature's arguments;
* a ``Returns`` (or ``Yields``) section unless the return annotation says None (a callable
  without a return annotation must document what it returns).

Pure Python, no numpydoc needed.
"""
from __future__ import annotations

import importlib
import inspect
import re

import pytest

PUBLIC_API = [
    ("spreadmap.case.identity", "case_id"),
    ("spreadmap.case.identity", "case_scene"),
    ("spreadmap.case.identity", "content_key"),
    ("spreadmap.case.identity", "is_legacy_id"),
    ("spreadmap.case.identity", "keyed_id"),
    ("spreadmap.case.identity", "readable_id"),
    ("spreadmap.case.identity", "readable_part"),
    ("spreadmap.case.identity", "repeat_group"),
    ("spreadmap.case.identity", "rounded"),
    ("spreadmap.case.launcher", "failure_record"),
    ("spreadmap.case.launcher", "retry_wanted"),
    ("spreadmap.case.launcher", "run_case"),
    ("spreadmap.case.launcher", "simulate"),
    ("spreadmap.case.launcher", "write_json_atomically"),
    ("spreadmap.case.migrate", "legacy_case_folders"),
    ("spreadmap.case.migrate", "migrate_case_folders"),
    ("spreadmap.case.pictures", "build_case_figure"),
    ("spreadmap.case.pictures", "choose_moments"),
    ("spreadmap.case.pictures", "plot_case_views"),
    ("spreadmap.case.pictures", "sphere_table"),
    ("spreadmap.case.pictures", "view_window"),
    ("spreadmap.case.render", "render"),
    ("spreadmap.case.render", "rendered_params"),
    ("spreadmap.case.render", "template_sha256"),
    ("spreadmap.case.scene", "UnsafeTimeStep"),
    ("spreadmap.case.scene", "precision_target"),
    ("spreadmap.case.scene", "scene_parameters"),
    ("spreadmap.case.substrate", "effective_gap_um"),
    ("spreadmap.case.substrate", "floor_label"),
    ("spreadmap.case.substrate", "floor_of"),
    ("spreadmap.case.substrate", "mean_hollow_depth"),
    ("spreadmap.case.vtk_export", "export_case"),
    ("spreadmap.case.vtk_export", "write_vtk"),
    ("spreadmap.config", "ConfigError"),
    ("spreadmap.config", "check_sections"),
    ("spreadmap.config", "load"),
    ("spreadmap.config", "renamed_keys"),
    ("spreadmap.config", "validate"),
    ("spreadmap.decisions", "decision_config"),
    ("spreadmap.decisions", "powders_from_config"),
    ("spreadmap.decisions", "recommendations"),
    ("spreadmap.decisions.explorer", "write_explorer"),
    ("spreadmap.decisions.figure", "decision_figure"),
    ("spreadmap.design", "Design"),
    ("spreadmap.design", "Parameter"),
    ("spreadmap.design", "bounds"),
    ("spreadmap.design", "h_over_d"),
    ("spreadmap.design", "to_physical"),
    ("spreadmap.design", "to_unit"),
    ("spreadlab.experiments.cost_study", "cpu_needed"),
    ("spreadlab.experiments.cost_study", "summarise"),
    ("spreadlab.experiments.noisy_study", "cases_needed"),
    ("spreadlab.experiments.noisy_study", "rmse_summary"),
    ("spreadlab.experiments.noisy_study", "run"),
    ("spreadlab.experiments.noisy_study", "summarise"),
    ("spreadlab.experiments.experiment_plots", "plot_cost_study"),
    ("spreadlab.experiments.experiment_plots", "plot_noisy_study"),
    ("spreadlab.experiments.experiment_plots", "plot_sampling_study"),
    ("spreadlab.experiments.replay", "build_world"),
    ("spreadlab.experiments.replay", "calibrate_margin"),
    ("spreadlab.experiments.replay", "honesty"),
    ("spreadlab.experiments.replay", "replay_one"),
    ("spreadlab.experiments.replay", "stops"),
    ("spreadlab.experiments.replay_plots", "plot_replay"),
    ("spreadlab.experiments.sampling_study", "flow_curve"),
    ("spreadlab.experiments.sampling_study", "study"),
    ("spreadlab.experiments.sampling_study", "summarise"),
    ("spreadlab.paired_factor", "config_block"),
    ("spreadlab.paired_factor", "correction"),
    ("spreadlab.paired_factor", "pairs"),
    ("spreadmap.fidelity.fidelity_plots", "correction_figure"),
    ("spreadmap.fidelity.fidelity_plots", "knobs_figure"),
    ("spreadmap.fidelity.fidelity_plots", "pareto_figure"),
    ("spreadmap.fidelity.study", "goal"),
    ("spreadmap.fidelity.study", "knob_errors"),
    ("spreadmap.fidelity.study", "machine_description"),
    ("spreadmap.fidelity.study", "markdown_summary"),
    ("spreadmap.fidelity.study", "preset_errors"),
    ("spreadmap.files", "atomic_path"),
    ("spreadmap.files", "write_csv_atomically"),
    ("spreadmap.files", "write_text_atomically"),
    ("spreadmap.logs", "log_to"),
    ("spreadmap.loop.cost", "PlannedCost"),
    ("spreadmap.loop.model", "make_map_fit"),
    ("spreadmap.loop.loop_plot", "plot_converge_path"),
    ("spreadlab.recheck", "path_rows"),
    ("spreadlab.recheck", "redecide"),
    ("spreadlab.recheck", "recheck_path"),
    ("spreadlab.recheck", "run_steps"),
    ("spreadmap.loop.stepper", "step"),
    ("spreadmap.loop.stepper", "step_number"),
    ("spreadlab.floors", "box_sample"),
    ("spreadlab.floors", "by_band"),
    ("spreadlab.floors", "compare"),
    ("spreadlab.floors", "piles_by_band"),
    ("spreadlab.floors_plot", "plot_ratio_box"),
    ("spreadlab.floors_plot", "plot_side_by_side"),
    ("spreadmap.maps.grids", "choose_machine_y"),
    ("spreadmap.maps.grids", "evaluate"),
    ("spreadmap.maps.grids", "f_effect"),
    ("spreadmap.maps.grids", "grid_frame"),
    ("spreadmap.maps.grids", "machine_y_axis"),
    ("spreadmap.maps.grids", "regime_probabilities"),
    ("spreadmap.maps.grids", "values"),
    ("spreadmap.maps.labels", "end_label"),
    ("spreadmap.maps.labels", "right_labels"),
    ("spreadmap.maps.labels", "which_labelled"),
    ("spreadmap.maps.machine", "machine_grid"),
    ("spreadmap.maps.machine", "machine_map"),
    ("spreadmap.maps.parallel", "best_case"),
    ("spreadmap.maps.parallel", "parallel_coordinates"),
    ("spreadmap.maps.powder_maps", "powder_band_map"),
    ("spreadmap.maps.powder_maps", "powder_cluster_map"),
    ("spreadmap.maps.regimes", "regime_overlay"),
    ("spreadmap.maps.style", "MapResult"),
    ("spreadmap.maps.style", "fmt"),
    ("spreadmap.maps.style", "set_limits"),
    ("spreadmap.maps.style", "support_note"),
    ("spreadmap.maps.style", "support_rule"),
    ("spreadmap.maps.style", "with_model_note"),
    ("spreadmap.maps.validation_note", "validation_note"),
    ("spreadmap.metrics", "case_metrics"),
    ("spreadmap.metrics.noise", "calibration_factors"),
    ("spreadmap.metrics.noise", "flow_trend_batch_z"),
    ("spreadmap.metrics.noise", "t_normal_score"),
    ("spreadmap.noise_law.apply", "case_noise"),
    ("spreadlab.noise_law.cells", "adhesive_cases"),
    ("spreadlab.noise_law.cells", "adhesive_cells"),
    ("spreadlab.noise_law.cells", "published_cells"),
    ("spreadlab.noise_law.counting", "counting_constant"),
    ("spreadlab.noise_law.counting", "pooled_constant"),
    ("spreadlab.noise_law.fit", "fit_law"),
    ("spreadlab.noise_law.fit", "likelihood_ratio"),
    ("spreadlab.noise_law.fit", "profile_interval"),
    ("spreadlab.noise_law.leave_one_out", "leave_point_out"),
    ("spreadlab.noise_law.leave_one_out", "predictive_check"),
    ("spreadlab.noise_law.leave_one_out", "scored"),
    ("spreadlab.noise_law.plot", "law_figure"),
    ("spreadlab.noise_law.refit", "config_entry"),
    ("spreadlab.noise_law.refit", "refit"),
    ("spreadlab.noise_law.refit", "refit_target"),
    ("spreadmap.records", "read_json_object"),
    ("spreadmap.records", "read_metrics"),
    ("spreadmap.records", "read_raw"),
    ("spreadmap.records", "read_table"),
    ("spreadmap.sampling", "halton"),
    ("spreadmap.sampling", "lattice"),
    ("spreadmap.schema", "checked"),
    ("spreadmap.schema", "section_schema"),
    ("spreadmap.sensitivity", "plot_ranking"),
    ("spreadmap.sensitivity", "sensitivity"),
    ("spreadlab.study.cases", "cpu_hours_to_go"),
    ("spreadlab.study.cases", "finished_table"),
    ("spreadlab.study.cases", "loop_cases"),
    ("spreadmap.sweeps", "loop_labels"),
    ("spreadmap.sweeps", "planned_cases"),
    ("spreadlab.study.cases", "planned_sweeps"),
    ("spreadlab.study.cases", "progress"),
    ("spreadlab.study.checksums", "PublishedFileError"),
    ("spreadlab.study.checksums", "check_folder"),
    ("spreadlab.study.checksums", "listed_files"),
    ("spreadlab.study.checksums", "republish_if_listed"),
    ("spreadlab.study.checksums", "sha256"),
    ("spreadlab.study.checksums", "verified_bytes"),
    ("spreadlab.study.checksums", "write_manifest"),
    ("spreadlab.study.restore", "UnkeyedTableError"),
    ("spreadlab.study.restore", "restore_cases"),
    ("spreadlab.study.restore", "restore_steps"),
    ("spreadlab.study.summary", "summary_markdown"),
    ("spreadlab.study.summary", "trends"),
    ("spreadmap.study_rule", "convergence_table"),
    ("spreadmap.study_rule", "first_stable_n"),
    ("spreadmap.study_rule", "running_statistics"),
    ("spreadmap.study_rule", "summary"),
    ("spreadmap.study_rule.rule_plots", "partition_values"),
    ("spreadmap.study_rule.rule_plots", "plot_distributions"),
    ("spreadmap.study_rule.rule_plots", "plot_statistics"),
    ("spreadmap.run_report", "run_summary"),
    ("spreadmap.run_report", "summary_text"),
    ("spreadmap.surrogate", "fit_map_model"),
    ("spreadmap.surrogate", "fit_surrogate"),
    ("spreadmap.surrogate", "validate_surrogate"),
    ("spreadmap.surrogate", "load_model"),
    ("spreadmap.surrogate", "save_model"),
    ("spreadmap.surrogate.cli", "cli_main"),
    ("spreadmap.surrogate.cli", "predict_logged"),
    ("spreadmap.surrogate.cli", "snakemake_main"),
    ("spreadmap.surrogate.cli", "write_csv"),
    ("spreadmap.surrogate.correction", "Correction"),
    ("spreadmap.surrogate.fitting", "chosen_models"),
    ("spreadlab.heldout_points", "choose_points"),
    ("spreadlab.heldout_points", "match_runs"),
    ("spreadlab.heldout_points", "runs_of"),
    ("spreadlab.heldout_points", "score"),
    ("spreadmap.surrogate.plots", "plot_all"),
    ("spreadmap.surrogate.plots", "plot_heldout"),
    ("spreadmap.surrogate.saved_model", "ModelFileError"),
    ("spreadmap.surrogate.settings", "map_config"),
    ("spreadmap.surrogate.validation", "verdict"),
    ("spreadmap.slices", "Slice"),
    ("spreadmap.slices", "axis_values"),
    ("spreadmap.slices", "box"),
    ("spreadmap.slices", "size_key"),
    ("spreadmap.slices", "text"),
    ("spreadmap.table", "build_table"),
    ("spreadmap.table", "usable"),
    ("spreadmap.table", "usable_cases"),
    ("spreadmap.table", "partition"),
    ("spreadmap.table", "write_table"),
]

SECTIONS = {"Parameters", "Returns", "Yields", "Receives", "Other Parameters", "Raises", "Warns", "Warnings",
            "See Also", "Notes", "References", "Examples", "Attributes", "Methods"}
UNDERLINE = re.compile(r"^-{3,}$")
ENTRY = re.compile(r"^(?P<names>[^:]+?) : (?P<type>\S.*)$")
NAME = re.compile(r"^\*{0,2}[A-Za-z_]\w*$")


def _callables():
    """(id, object, what) for every function, class and public method of PUBLIC_API."""
    out = []
    for module, name in PUBLIC_API:
        obj = getattr(importlib.import_module(module), name)
        qual = f"{module}.{name}"
        if inspect.isclass(obj):
            out.append((qual, obj, "class"))
            for attr, member in vars(obj).items():
                if attr.startswith("_") or isinstance(member, property):
                    continue
                if isinstance(member, (classmethod, staticmethod)) or inspect.isfunction(member):
                    out.append((f"{qual}.{attr}", getattr(obj, attr), "method"))
        else:
            out.append((qual, obj, "function"))
    return out


CALLABLES = _callables()


def sections(doc: str) -> dict[str, list[str]]:
    """Header -> the lines under its underline, up to the next header (docstring dedented)."""
    lines = inspect.cleandoc(doc).splitlines()
    heads = [i for i in range(len(lines) - 1) if lines[i].strip() and UNDERLINE.match(lines[i + 1].strip())]
    return {lines[i].strip(): lines[i + 2:(heads[k + 1] if k + 1 < len(heads) else len(lines))]
            for k, i in enumerate(heads)}


def documented_parameters(lines: list[str]) -> list[str]:
    """The names of a Parameters section's entries; each entry must read `name : type` and be
    followed by an indented description."""
    names = []
    for i, line in enumerate(lines):
        if not line.strip() or line[0].isspace():
            continue
        m = ENTRY.match(line.rstrip())
        assert m, f"Parameters entry {line!r} is not of the form 'name : type'"
        following = lines[i + 1] if i + 1 < len(lines) else ""
        assert following[:1].isspace() and following.strip(), f"Parameters entry {line!r} has no description"
        for name in (n.strip() for n in m["names"].split(",")):
            assert NAME.match(name), f"{name!r} in {line!r} is not a parameter name"
            names.append(name.lstrip("*"))
    return names


def signature_parameters(obj, what: str) -> list[str] | None:
    """The arguments a caller passes (self/cls dropped); None when there is no signature to check
    (an exception class that keeps its base's constructor)."""
    if what == "class" and "__init__" not in vars(obj) and not hasattr(obj, "__dataclass_fields__"):
        return None
    sig = inspect.signature(obj)
    return [p for p in sig.parameters if p not in ("self", "cls")]


def returns_nothing(obj, what: str) -> bool:
    if what == "class":
        return True
    annotation = inspect.signature(obj).return_annotation
    return annotation is None or annotation == "None"


@pytest.mark.parametrize("qual, obj, what", CALLABLES, ids=[c[0] for c in CALLABLES])
def test_numpydoc(qual, obj, what):
    doc = obj.__doc__
    assert doc and doc.strip(), f"{qual}: no docstring"
    assert inspect.cleandoc(doc).splitlines()[0].strip(), f"{qual}: no summary line"
    found = sections(doc)
    unknown = set(found) - SECTIONS
    assert not unknown, f"{qual}: section(s) {sorted(unknown)} are not numpydoc sections"

    params = signature_parameters(obj, what)
    if params:
        assert "Parameters" in found, f"{qual}: takes {params} but has no Parameters section"
        named = documented_parameters(found["Parameters"])
        missing = [p for p in params if p not in named]
        extra = [p for p in named if p not in params]
        assert not missing, f"{qual}: parameter(s) {missing} not documented"
        assert not extra, f"{qual}: documents {extra}, which the signature does not have"
        assert len(named) == len(set(named)), f"{qual}: a parameter is documented twice"
    if not returns_nothing(obj, what):
        body = [line for key in ("Returns", "Yields") for line in found.get(key, []) if line.strip()]
        assert body, f"{qual}: returns a value but has no Returns (or Yields) section"


def test_public_api_listed_once():
    assert len(PUBLIC_API) == len(set(PUBLIC_API))


def test_parser_reads_numpydoc():
    def f(a, b=1, *args, **kwargs):
        """Summary.

        Parameters
        ----------
        a, b : int
            Numbers.
        *args : tuple
            More.
        **kwargs : dict
            Options.

        Returns
        -------
        int
            A number.
        """

    found = sections(f.__doc__)
    assert set(found) == {"Parameters", "Returns"}
    assert documented_parameters(found["Parameters"]) == ["a", "b", "args", "kwargs"]
    assert signature_parameters(f, "function") == ["a", "b", "args", "kwargs"]
    with pytest.raises(AssertionError):
        documented_parameters(["a: int", "    no space before the colon"])
