"""The product and the lab (issue 65): spreadmap never imports spreadlab; spreadmap's imports have
no cycle; the product's stages import no later stage; the workflow's entry points reach the lab
only for the one study the Snakefile runs from it.

Read with ast (tools/import_graph.py), not by importing: a function-local import counts, since it
runs when the function does.
"""
import ast

import pytest
from conftest import ROOT, script_module

graphs = script_module("tools/import_graph.py")

# the product's path, in the order the main job works; no module of a stage imports a later one
STAGES = ("spreadmap.config", "spreadmap.case", "spreadmap.metrics", "spreadmap.table", "spreadmap.loop",
          "spreadmap.surrogate", "spreadmap.maps", "spreadmap.decisions")
# on purpose: the loop's model is the map's model, the surrogate's own GP or MLP and its settings
# (spreadmap/loop/model.py), so that "converged" means the maps' model has converged
LATER_STAGE_ON_PURPOSE = {("spreadmap.loop.model", "spreadmap.surrogate"),
                          ("spreadmap.loop.model", "spreadmap.surrogate.models"),
                          ("spreadmap.loop.model", "spreadmap.surrogate.settings")}
# the entry points that may import the lab: the DEM-free sampling study (`snakemake sampling`)
LAB_ENTRY_POINTS = {"scripts/sampling_study.py"}


def _lab_imports(path, module: str | None, is_package: bool = False) -> list[str]:
    """The imports of a file that name spreadlab: `import`, `from ... import` (relative ones resolved
    against `module`) and importlib.import_module / __import__ of a literal name, at any depth."""
    tree = ast.parse(path.read_text(), filename=str(path))
    found = []
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = module.split(".") if is_package else module.split(".")[:-1]
                parts = parts[:max(len(parts) - (node.level - 1), 0)]
                names = [".".join(parts + ([node.module] if node.module else []))]
            else:
                names = [node.module]
            names += [f"{names[0]}.{alias.name}" if names[0] else alias.name for alias in node.names]
        elif (isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant)
              and getattr(node.func, "attr", getattr(node.func, "id", None)) in ("import_module", "__import__")):
            names = [str(node.args[0].value)]
        found += [f"line {node.lineno}: {n}" for n in names if n == "spreadlab" or n.startswith("spreadlab.")]
    return found


def test_no_module_of_spreadmap_imports_spreadlab():
    modules = graphs.package_modules(ROOT, ("spreadmap",))
    found = {name: hits for name, path in modules.items()
             if (hits := _lab_imports(path, name, path.name == "__init__.py"))}
    assert not found, f"the product imports the lab (the lab imports the product, never the reverse): {found}"


def test_the_check_sees_an_import_of_the_lab(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text("def f():\n    from spreadlab.recheck import recheck\n"
                     "import importlib\nimportlib.import_module('spreadlab.floors')\nfrom .... import spreadlab\n")
    assert sorted(hit.split(": ")[1] for hit in _lab_imports(probe, "spreadmap.maps.probe")) == [
        "spreadlab", "spreadlab.floors", "spreadlab.recheck", "spreadlab.recheck.recheck"]


def test_spreadmap_s_imports_have_no_cycle():
    cycles = graphs.cycles(graphs.graph(ROOT, ("spreadmap",)))
    assert not cycles, f"import cycles in spreadmap (each: modules that import one another round): {cycles}"


def test_the_cycle_finder_finds_one():
    edges = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert graphs.cycles(edges) == [["a", "b", "c"]]


def _stage(module: str) -> int | None:
    return next((i for i, s in enumerate(STAGES) if module == s or module.startswith(s + ".")), None)


def test_no_stage_of_the_product_imports_a_later_one():
    edges = graphs.graph(ROOT, ("spreadmap",))
    back = sorted((m, t) for m, targets in edges.items() for t in targets
                  if _stage(m) is not None and _stage(t) is not None and _stage(t) > _stage(m))
    assert set(back) <= LATER_STAGE_ON_PURPOSE, f"back-arrows on the product's path {STAGES}: " \
                                                f"{sorted(set(back) - LATER_STAGE_ON_PURPOSE)}"


def test_config_imports_only_the_ground_floor():
    """config validates every section, yet imports no stage above it: the owners' checks are handed
    in (spreadmap/__init__.py wires them)."""
    assert graphs.graph(ROOT, ("spreadmap",))["spreadmap.config"] <= {"spreadmap.schema", "spreadmap.targets"}


@pytest.mark.parametrize("path", [*graphs.entry_point_files(ROOT)], ids=lambda p: str(p.relative_to(ROOT)))
def test_the_workflow_s_entry_points_import_no_lab_but_its_one_study(path):
    modules = graphs.package_modules(ROOT)
    lab = sorted(m for m in graphs.entry_point_imports(path, modules) if m.startswith("spreadlab"))
    if str(path.relative_to(ROOT)) in LAB_ENTRY_POINTS:
        return
    assert not lab, f"{path.relative_to(ROOT)} imports the lab: {lab}"


def test_every_module_of_spreadmap_is_reached_by_the_product():
    """A module no entry point of the workflow reaches (scripts/*.py, the Snakefile, rules/*.smk)
    belongs to the lab, unless the product's users run it by hand: case.retry serves
    tools/retry_failed.py on a workflow directory of the product's."""
    unreached = sorted(set(graphs.package_modules(ROOT, ("spreadmap",))) - graphs.reached(ROOT))
    assert unreached == ["spreadmap.case.retry"], unreached
