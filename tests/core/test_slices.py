"""The slices' one home, spreadmap.slices (issue 65, item 4): the maps, the decisions and the loop's
criteria read the same points as before, from one definition each; a fifth design axis registered in
spreadmap.design alone reaches the slices, the sample table, the maps' grids, the decisions and the
criteria' grids; and a new axis touches at most five files."""
import ast
import re

import numpy as np
import pandas as pd
import pytest
import yaml
from conftest import ROOT

from spreadmap import design, sampling, slices
from spreadmap.decisions import explorer
from spreadmap.decisions.config_section import decision_config
from spreadmap.decisions.feasibility import Powder, feasibility, setting_grid
from spreadmap.loop import map_criteria
from spreadmap.maps import machine, powder_maps, regimes
from spreadmap.schema import checked

MAPS = checked("maps")  # the schema's defaults: f 0.45, d_um 45 (machine); h_um 57, v_mm_s 6.1 (powder)
LOW = {p.name: p.low for p in design.PARAMETERS}
HIGH = {p.name: p.high for p in design.PARAMETERS}


def mesh(**cols) -> np.ndarray:
    """Points of the tensor grid, the first parameter of NAMES slowest, as the maps always built them."""
    m = np.meshgrid(*[np.atleast_1d(np.asarray(cols[n], float)) for n in design.NAMES], indexing="ij")
    return np.column_stack([x.ravel() for x in m])


def span(name, n, ranges=None):
    lo, hi = (ranges or {}).get(name, {}).get("min", LOW[name]), (ranges or {}).get(name, {}).get("max", HIGH[name])
    return np.linspace(lo, hi, n)


def test_the_slices_are_the_config_values_on_linspaces_of_the_ranges():
    """On the default config each slice is its config's fixed values on np.linspace of the design
    ranges, to the bit: machine 5 x 5 (h, v) at f 0.45, d 45 um; powder 5 x 41 (f, d) at h 57 um,
    v 6.1 mm/s; regime plane 60 x 40 (d, h) at f 0.3, v 10 mm/s; decisions 21 x 21 (h, v) over
    decisions.machine's limits; the loop's box 5^4 cell centres."""
    mach, powd, plane = MAPS["machine"], MAPS["powder"], MAPS["regime_plane"]
    assert (mach["f"], mach["d_um"], powd["h_um"], powd["v_mm_s"]) == (0.45, 45, 57, 6.1)  # SPEC's
    machine_points = mesh(f=mach["f"], d_um=mach["d_um"], h_um=span("h_um", mach["n_h"]),
                          v_mm_s=span("v_mm_s", mach["n_v"]))
    powder_points = mesh(f=span("f", 5), d_um=span("d_um", 41), h_um=powd["h_um"], v_mm_s=powd["v_mm_s"])
    plane_points = mesh(f=plane["f"], d_um=span("d_um", 60), h_um=span("h_um", 40), v_mm_s=plane["v_mm_s"])
    assert np.array_equal(slices.MACHINE.points(), machine_points)
    assert np.array_equal(slices.POWDER.points(), powder_points)
    assert np.array_equal(slices.REGIME_PLANE.points(), plane_points)
    centres = (np.arange(5) + 0.5) / 5
    box = mesh(**{n: LOW[n] + centres * (HIGH[n] - LOW[n]) for n in design.NAMES})
    grids = map_criteria.map_grids()
    assert np.array_equal(grids["box"], box)
    assert np.array_equal(grids["machine"], machine_points) and np.array_equal(grids["powder"], powder_points)
    dec = decision_config(None)["machine"]
    h, v = setting_grid(decision_config(None))
    assert np.array_equal(h, np.linspace(*dec["h_um"], dec["n_h"])) and np.array_equal(v, np.linspace(*dec["v_mm_s"], dec["n_v"]))


def test_the_slices_follow_the_config_and_the_ranges():
    """A config's fixed values and grid sizes and its design ranges reach the slice and the loop's
    grids alike."""
    config = {"maps": {"machine": {"f": 0.2, "d_um": 20, "n_h": 3, "n_v": 4}, "powder": {"h_um": 60, "v_mm_s": 8}},
              "ranges": {"h_um": {"min": 50, "max": 80}}}
    expected = mesh(f=0.2, d_um=20, h_um=span("h_um", 3, config["ranges"]), v_mm_s=span("v_mm_s", 4))
    assert np.array_equal(slices.MACHINE.points(config), expected)
    grids = map_criteria.map_grids(config["maps"], config["ranges"], box_k=3, n_d=7, n_f=2)
    assert np.array_equal(grids["machine"], expected)
    assert np.array_equal(grids["powder"], mesh(f=span("f", 2), d_um=span("d_um", 7), h_um=60, v_mm_s=8))
    assert grids["box"].shape == (3 ** len(design.NAMES), len(design.NAMES))


def test_a_decision_slice_holds_every_powder_of_a_range_at_each_setting():
    """The decisions' slice: each (h, v) setting, h slowest, with every powder of the range (f slowest)."""
    powder = Powder("p", (0.2, 0.3), (20.0, 30.0))
    h, v = np.linspace(55, 75, 4), np.linspace(5, 15, 3)
    points = slices.DECISIONS.frame({"h_um": h, "v_mm_s": v}, powder.points(3)).to_numpy(float)
    settings = np.array([(hh, vv) for hh in h for vv in v])
    powders = np.array([(f, d) for f in np.linspace(0.2, 0.3, 3) for d in np.linspace(20, 30, 3)])
    expected = np.column_stack([np.tile(powders, (len(settings), 1)), np.repeat(settings, len(powders), axis=0)])
    assert np.array_equal(points, expected)


def test_slices_refuse_what_is_not_a_grid():
    with pytest.raises(ValueError, match="grid size for h_um"):
        slices.MACHINE.points(sizes={"h_um": 1})
    with pytest.raises(ValueError, match="no values given for f"):
        slices.POWDER.axes(given={"f": []})


# ------------------------------------------------------------------------------------------------
# a toy fifth axis
# ------------------------------------------------------------------------------------------------
TOY = design.Parameter("w_mm", "w", "blade width w [mm]", 1.0, 3.0, "mm", nominal=2.0)


@pytest.fixture
def toy_axis(monkeypatch):
    """The registry with a fifth axis, as a new axis is added: one Parameter in spreadmap.design."""
    params = (*design.PARAMETERS, TOY)
    monkeypatch.setattr(design, "PARAMETERS", params)
    monkeypatch.setattr(design, "NAMES", tuple(p.name for p in params))
    monkeypatch.setattr(design, "BY_NAME", {p.name: p for p in params})
    return TOY


class Toy5:
    """A stand-in surrogate over whatever axes it is given: each target a known linear function of
    every column (the last, the toy axis, included), constant SDs, every point at the data, draws
    the mean plus a shared normal; it keeps the points it was asked about."""

    targets = ("mfr", "pd", "coverage", "thickness_ratio")
    correction = None

    def __init__(self):
        space = design.Design.of(None)
        self.design_low, self.design_high = space.bounds()
        self.train_X = sampling.halton(40, 0)[list(design.NAMES)].to_numpy(float)
        self.seen = []

    def mean(self, X):
        X = np.asarray(X, float)
        self.seen.append(X)
        u = design.Design.of(None).to_unit(X)
        return 0.2 + 0.1 * u.sum(axis=1)

    def predict_stats(self, X):
        m = self.mean(X)
        return {t: (m, np.full(len(m), 0.01), np.full(len(m), 0.03)) for t in self.targets}

    def data_distance(self, X):
        return np.zeros(len(X))

    def spacing(self):
        return 0.1

    def draws(self, X, n, seed=0, targets=None):
        z = np.random.default_rng(seed).standard_normal((n, 1))
        return {t: self.mean(X)[None, :] + 0.01 * z for t in (targets or self.targets)}


def test_a_toy_axis_registered_once_reaches_the_slices_the_sample_and_the_maps(toy_axis):
    """Registered in spreadmap.design alone, a fifth axis (blade width w, 1-3 mm, nominal 2 mm) is a
    column of the sample table and of every slice, held at its nominal value where a slice fixes it
    (or at a value a config names), and the maps' grid builders, the decisions and the loop's grids
    carry it to the model."""
    names = design.NAMES
    assert names[-1] == "w_mm" and len(names) == 5
    table = sampling.halton(16, 3)
    assert list(table.columns) == ["index", *names]
    assert table["w_mm"].between(1.0, 3.0).all() and table["w_mm"].nunique() == 16
    for s in slices.SLICES.values():
        assert "w_mm" in s.fixed_axes()
    assert slices.MACHINE.fixed(slices.MACHINE.settings()) == {"f": 0.45, "d_um": 45.0, "w_mm": 2.0}
    assert slices.MACHINE.fixed({"w_mm": 2.5})["w_mm"] == 2.5
    assert slices.text({"v_mm_s": 6.1, "w_mm": 2.0}) == "v = 6.1 mm/s, w = 2 mm"

    grids = map_criteria.map_grids(box_k=2)
    assert grids["box"].shape == (2 ** 5, 5)
    assert np.all(grids["machine"][:, -1] == 2.0) and np.all(grids["powder"][:, -1] == 2.0)

    model = Toy5()
    support = MAPS["support"]
    built = {"machine": machine.machine_grid(model, "pd", n_h=3, n_v=2, support=support),
             "band": powder_maps.powder_band_grid(model, "pd", n_d=3, n_f=2, draws=8, support=support),
             "cluster": powder_maps.powder_cluster_grid(model, "pd", n_d=2, n_f=2, support=support)}
    cases = sampling.halton(12, 1).assign(mfr=0.3, pd=0.5, regime="normal")
    built["regime"] = regimes.regime_tables(cases, model, checked("regime", {"jam_mfr_max": 0.05,
                                            "short_feed_coverage_min": 0.5, "short_feed_thickness_min": 0.3}),
                                            n_d=3, n_h=2, support=support)[1]
    for name, frame in built.items():
        assert list(frame.columns[:5]) == list(names), name
        assert np.all(frame["w_mm"] == 2.0), name
    assert all(X.shape[1] == 5 for X in model.seen)

    dec = decision_config({"machine": {"h_um": [55, 75], "v_mm_s": [5, 15], "n_h": 2, "n_v": 2},
                           "bounds": {"coverage": {"min": 0.3}}, "draws": 16,
                           "explorer": {"n_f": 2, "n_d": 2, "n_h": 2, "n_v": 2}})
    model.seen.clear()
    grid = feasibility(model, Powder("p", (0.2, 0.3), (20.0, 20.0)), [55, 75], [5, 15], dec["bounds"],
                       dec["quality"], support, draws=16, range_points=2)
    assert len(grid) == 4 and all(X.shape[1] == 5 and np.all(X[:, -1] == 2.0) for X in model.seen)
    page = explorer.explorer_data(model, dec, support)
    assert len(page["mean"]["pd"]) == 16


# ------------------------------------------------------------------------------------------------
# how many files a new axis touches
# ------------------------------------------------------------------------------------------------
AXIS_FILES = {
    "spreadmap/design.py": "the axis: a Parameter (name, symbol, label, default range, unit, nominal)",
    "schemas/config.schema.yaml": "its `ranges` entry and its key of a chosen point (`definitions.point`): the "
                                  "schema refuses names it does not know; a slice holding it at another value than "
                                  "the nominal names it in that slice's section",
    "spreadmap/case/scene.py": "its value into the scene's parameters, in the simulation's units",
    "spreadmap/case/identity.py": "its digits and its place in the readable case id",
    "yade_scripts/spreading_case.py": "the physics: what the simulation does with it",
}
# files that still enumerate the axes and belong to the refactors running beside this one (issue 65):
# the case pictures (the scene's spreadmap/case) and the floors' comparison (moving into spreadlab)
ELSEWHERE = {"spreadmap/case/pictures.py"}


def enumerations(path) -> list[tuple[int, list[str]]]:
    """Where a Python file spells out three or more design axes together: a tuple, list, set or
    dict's keys of their names, a call's or a function's arguments named after them, an f-string
    reading them by name."""
    names = set(design.NAMES)
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.Tuple, ast.List, ast.Set, ast.Dict)):
            items = node.keys if isinstance(node, ast.Dict) else node.elts
            got = {n.value for n in items if isinstance(n, ast.Constant) and n.value in names}
        elif isinstance(node, ast.Call):
            got = {k.arg for k in node.keywords} & names
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            got = {a.arg for a in node.args.args + node.args.kwonlyargs} & names
        elif isinstance(node, ast.JoinedStr):
            got = {n.slice.value for n in ast.walk(node) if isinstance(n, ast.Subscript)
                   and isinstance(n.slice, ast.Constant) and n.slice.value in names}
        else:
            continue
        if len(got) >= 3:
            out.append((node.lineno, sorted(got)))
    return out


def test_a_new_axis_touches_at_most_five_files():
    """A fifth design axis touches five files:

    1. spreadmap/design.py -- the axis: a Parameter (name, symbol, label, default range, unit, nominal);
    2. schemas/config.schema.yaml -- its ``ranges`` entry and its key of a chosen point;
    3. spreadmap/case/scene.py -- its value into the scene's parameters;
    4. spreadmap/case/identity.py -- its digits and its place in the case id;
    5. yade_scripts/spreading_case.py -- the physics.

    The maps, the decisions, the loop's criteria, the sample and the tables take it from the
    registry (the toy axis above; a slice holds it at its nominal value). Checked here: no other
    Python file of the package, the scripts or the tools spells out the axes together (a tuple or
    dict of three or more of their names, a call or function with arguments named after them, an
    f-string reading them by name), but for the files of the refactors running beside this one
    (``ELSEWHERE``); the schema's ranges and chosen point name the registry's axes; docs/guide/06-workflow.md's
    recipe names the same five files. (config.yaml need not change: a range it leaves out is the
    registry's default.)"""
    assert len(AXIS_FILES) <= 5 and all((ROOT / f).is_file() for f in AXIS_FILES)
    files = [*ROOT.glob("spreadmap/**/*.py"), *ROOT.glob("scripts/*.py"), *ROOT.glob("tools/*.py")]
    found = {str(p.relative_to(ROOT)): hits for p in files if (hits := enumerations(p))}
    assert set(found) - ELSEWHERE <= set(AXIS_FILES), {k: v for k, v in found.items() if k not in AXIS_FILES}
    schema = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())["properties"]
    assert list(schema["ranges"]["properties"]) == list(design.NAMES)
    point = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())["definitions"]["point"]
    assert point["required"] == list(design.NAMES) == [k for k in point["properties"] if k not in ("preset", "seed")]
    recipe = (ROOT / "docs" / "guide" / "06-workflow.md").read_text().split("### Adding a design axis")[1]
    recipe = recipe.split("\n## ")[0].split("\n### ")[0]
    assert set(re.findall(r"`([\w/.-]+\.(?:py|yaml))`", recipe)) >= set(AXIS_FILES)


def test_the_enumeration_check_sees_an_enumeration(tmp_path):
    path = tmp_path / "x.py"
    path.write_text('COLS = ["f", "d_um", "h_um"]\ndef g(f, d_um, h_um, v_mm_s):\n    return f\n'
                    'ok = ["f", "d_um"]\n')
    assert sorted(line for line, _ in enumerations(path)) == [1, 2]


def test_a_slice_table_reads_back(tmp_path):
    """A map's CSV read back names its fixed axes (the titles read them from the table)."""
    frame = slices.POWDER.frame({"f": [0.2, 0.3], "d_um": [20.0]}, {"h_um": 60.0, "v_mm_s": 8.0})
    frame.to_csv(tmp_path / "x.csv", index=False)
    assert slices.POWDER.fixed_of(pd.read_csv(tmp_path / "x.csv")) == {"h_um": 60.0, "v_mm_s": 8.0}
