"""The main job's DAG on real Snakemake, planned without running anything (`snakemake -n`), and
the workflow's lint. Cheap: no YADE, a few seconds each."""
import re
import subprocess

from conftest import ROOT, SNAKEMAKE, make_workflow, planned_jobs, snakemake, write_config

DROP = ("points", "pictures")  # the tests give their own


def test_main_job_plans_without_chosen_points(tmp_path):
    """With no chosen points there is nothing to predict: the main job plans without the predict
    job (which would fail on an empty list of points) and still trains the surrogate."""
    wf = make_workflow(tmp_path, {"points": {"named": {}}, "pictures": {"cases": [], "vtk": []}}, DROP)
    dry = snakemake(wf, "-n")
    assert dry.returncode == 0, dry.stderr[-3000:]
    jobs = planned_jobs(dry.stdout)
    assert "predict" not in jobs and "results/surrogate/predictions.csv" not in dry.stdout
    assert jobs["surrogate"] == 1 and jobs["surrogate_validation"] == 1 and jobs["all"] == 1
    # issue 52: the MLP ensemble's machine and powder maps beside the map model's, asked for by the main job
    assert jobs["surrogate_mlp"] == 1 and jobs["maps_mlp"] == 1
    for name in ("machine_map_mlp.png", "powder_band_map_mlp.png", "machine_map.png", "powder_band_map.png"):
        assert f"results/maps/{name}" in dry.stdout, name


def test_main_job_predicts_the_chosen_points(tmp_path):
    wf = make_workflow(tmp_path, {"points": {"named": {"one": {"f": 0.3, "d_um": 30, "h_um": 65, "v_mm_s": 10}}},
                                  "pictures": {"cases": [], "vtk": []}}, DROP)
    dry = snakemake(wf, "-n")
    assert dry.returncode == 0, dry.stderr[-3000:]
    assert planned_jobs(dry.stdout)["predict"] == 1


def rule_edges(dot: str) -> set[tuple[str, str]]:
    """(upstream rule, downstream rule) of `snakemake --rulegraph`'s dot text."""
    labels = dict(re.findall(r'^\s*(\d+)\[label = "(\w+)"', dot, re.M))
    return {(labels[a], labels[b]) for a, b in re.findall(r"^\s*(\d+) -> (\d+)", dot, re.M)}


def upstream(edges: set[tuple[str, str]], rule: str) -> set[str]:
    """Every rule that `rule` waits for."""
    found, todo = set(), [rule]
    while todo:
        below = todo.pop()
        for a, b in edges:
            if b == below and a not in found:
                found.add(a)
                todo.append(a)
    return found


def test_the_maps_do_not_wait_for_the_surrogates_validation(tmp_path):
    """Issue 50: the map model and its validation are two rules; the maps, the decisions, the
    explorer and the predictions wait for the model only, the main job (and its timeline) for both.
    With `surrogate.model: best` the validation chooses the model: the model waits for it."""
    point = {"one": {"f": 0.3, "d_um": 30, "h_um": 65, "v_mm_s": 10}}
    wf = make_workflow(tmp_path, {"points": {"named": point}, "pictures": {"cases": [], "vtk": []}}, DROP)
    graph = snakemake(wf, "--rulegraph")
    assert graph.returncode == 0, graph.stderr[-3000:]
    edges = rule_edges(graph.stdout)
    for rule in ("maps", "decide", "explorer", "predict"):
        before = upstream(edges, rule)
        assert "surrogate" in before and "surrogate_validation" not in before, (rule, before)
    assert {("surrogate_validation", "all"), ("surrogate_validation", "timeline")} <= edges
    assert ("converge_table", "surrogate_validation") in edges and ("converge_table", "surrogate") in edges
    assert "surrogate_validation" not in upstream(edges, "surrogate")
    # the MLP's maps read its validation; its model waits for the table alone, and nothing of the map
    # model's path waits for either
    assert {"surrogate_mlp", "surrogate_validation"} <= upstream(edges, "maps_mlp")
    assert "surrogate_validation" not in upstream(edges, "surrogate_mlp")
    for rule in ("maps", "decide", "explorer", "predict", "surrogate_validation"):
        assert not {"surrogate_mlp", "maps_mlp"} & upstream(edges, rule), rule
    assert {("maps_mlp", "all"), ("maps_mlp", "timeline")} <= edges

    write_config(wf, {"points": {"named": point}, "pictures": {"cases": [], "vtk": []},
                      "surrogate": {"model": "best"}}, DROP)
    best = snakemake(wf, "--rulegraph")
    assert best.returncode == 0, best.stderr[-3000:]
    assert ("surrogate_validation", "surrogate") in rule_edges(best.stdout)


def test_lint_is_clean():
    """`snakemake --lint` on the shipped workflow reports nothing (the README says so)."""
    lint = subprocess.run([SNAKEMAKE, "--lint"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    out = lint.stdout + lint.stderr
    assert lint.returncode == 0 and "Lints for" not in out, out[-3000:]


def test_the_stated_runtime_of_a_reference_case_is_what_snakemake_asks_for(tmp_path):
    """The SLURM profile and the README tell a cluster user how long a reference case's job asks
    for; the number is the one Snakemake plans (read from the dry run), not a stale estimate."""
    point = {"f": 0.3, "d_um": 12, "h_um": 65, "v_mm_s": 10, "preset": "reference"}
    wf = make_workflow(tmp_path, {"points": {"named": {"small": point}}, "pictures": {"cases": [], "vtk": []}}, DROP)
    dry = snakemake(wf, "points", "-n")
    assert dry.returncode == 0, dry.stderr[-3000:]
    runtimes = {int(m) for m in re.findall(r"\bruntime=(\d+)\b", dry.stdout)}
    assert len(runtimes) == 1, runtimes
    minutes = runtimes.pop()
    profile = " ".join(line.lstrip("# ") for line in (ROOT / "profiles" / "slurm" / "config.yaml").read_text().split("\n"))
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert f"fixed 2 h timeout asks for {minutes} min" in profile
    assert f"so its jobs ask for {minutes} min" in readme


def test_one_lattice_size_plans_alone(tmp_path):
    """results/tables/lattice_k3.csv: the 3^4 lattice's cases and table, none of the 4^4's (a long
    study runs the smaller lattice to the end first); the whole lattice's table plans both, the
    16 corners they share once."""
    wf = make_workflow(tmp_path, {"sweeps": {"lattice": {"k": [3, 4]}}, "points": {"named": {}},
                                  "pictures": {"cases": [], "vtk": []}}, DROP)
    one = snakemake(wf, "-n", "results/tables/lattice_k3.csv")
    assert one.returncode == 0, one.stderr[-3000:]
    assert planned_jobs(one.stdout)["run_case"] == 3 ** 4 and planned_jobs(one.stdout)["results_table"] == 1
    both = snakemake(wf, "-n", "results/tables/lattice.csv")
    assert both.returncode == 0, both.stderr[-3000:]
    assert planned_jobs(both.stdout)["run_case"] == 3 ** 4 + 4 ** 4 - 2 ** 4
