"""Tests of the fidelity study without YADE: which cases it plans (spreadmap.fidelity.plan) and
the errors, noise, costs and figures it reports (spreadmap.fidelity.study, fidelity.fidelity_plots)."""
import copy
import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from spreadmap import config as spreadmap_config
from spreadmap.case.scene import scene_parameters
from spreadmap.fidelity import fidelity_plots, plan, study


@pytest.fixture(scope="module")
def shipped():
    return spreadmap_config.load("config.yaml")


# ---------------------------------------------------------------------------------------------
# the plan
# ---------------------------------------------------------------------------------------------
def test_knob_presets_change_one_key_of_the_base_preset(shipped):
    presets = plan.knob_presets(shipped)
    base = shipped["presets"][shipped["fidelity"]["knobs"]["preset"]]
    expected = sum(len([v for v in vals if v != base[k]]) for k, vals in shipped["fidelity"]["knobs"]["values"].items())
    assert len(presets) == expected
    for name, preset in presets.items():
        changed = [k for k in plan.KNOBS if preset[k] != base[k]]
        assert len(changed) == 1, name
        assert name == plan.knob_preset_name("default", changed[0], preset[changed[0]])


def test_preset_names_are_case_id_safe():
    assert plan.knob_preset_name("default", "dt_factor", 0.15) == "default_dt_factor_0p15"
    assert plan.knob_preset_name("default", "density_scale", 10000) == "default_density_scale_10000"
    assert plan.value_token(1e-5) == "1em05"


def test_plan_counts_and_the_base_value_is_shared(shipped):
    fid = shipped["fidelity"]
    rows = plan.preset_cases(shipped)
    assert len(rows) == len(fid["points"]) * len(fid["presets"]) * len(fid["seeds"])
    assert rows[-1]["preset"] == fid["reference"]
    knobs = plan.knob_cases(shipped)
    base_rows = [r for r in knobs if r["is_base"]]
    # every knob's sweep holds the base preset's own cases, with the base preset's name
    assert {r["knob"] for r in base_rows} == set(fid["knobs"]["values"])
    assert {r["preset"] for r in base_rows} == {fid["knobs"]["preset"]}
    for r in knobs:
        assert r["name"] == fid["knobs"]["point"]


def test_a_knob_preset_changes_only_what_its_knob_drives(shipped):
    cfg = copy.deepcopy(shipped)
    cfg["presets"].update(plan.knob_presets(cfg))
    point = cfg["fidelity"]["points"]["normal"]
    base = scene_parameters(point, "default", cfg, "x")
    dt = scene_parameters(point, "default_dt_factor_0p15", cfg, "x")
    assert dt["time_step"] == pytest.approx(0.5 * base["time_step"])
    assert dt["n_particles"] == base["n_particles"]
    wide = scene_parameters(point, "default_width_d_16", cfg, "x")
    assert wide["width"] == pytest.approx(16 / 10 * base["width"])
    # the pile holds what must pass before it is fed: a full pile (no scene.fed_heap) holds the
    # window's spheres too, so a wider bed makes it shorter (they spread over the width); what passes
    # in the transient and the standing reserve (scene.pile_reserve x h^2 per unit width) do not
    # shrink: a pile of fixed length would hold 16/10 as many spheres. A fed pile holds no window:
    # its length does not depend on the width, its spheres grow as the width
    if cfg["scene"]["fed_heap"]:
        assert wide["pile_length"] == pytest.approx(base["pile_length"], rel=1e-12)
        assert wide["n_particles"] == pytest.approx(16 / 10 * base["n_particles"], abs=1)
        assert wide["feed_count"] == pytest.approx(16 / 10 * base["feed_count"], abs=1)
    else:
        assert wide["pile_length"] < base["pile_length"]
        assert base["n_particles"] < wide["n_particles"] < 16 / 10 * base["n_particles"]
    reserve = cfg["scene"]["pile_reserve"] * point["h_um"] ** 2 / (point["h_um"] + 10 * point["d_um"]) * 1e-6
    # (on a full pile: a fed pile without its reserve is shorter than the preset's minimum here)
    full = copy.deepcopy(cfg)
    full["scene"]["fed_heap"] = False
    no_reserve = copy.deepcopy(full)
    no_reserve["scene"]["pile_reserve"] = 0.0
    assert scene_parameters(point, "default", full, "x")["pile_length"] - \
        scene_parameters(point, "default", no_reserve, "x")["pile_length"] == \
        pytest.approx(reserve, rel=1e-9)  # 4.7 h^2 / (h + heap): 1.8 d at this point
    precise = scene_parameters(point, "default_target_cv_0p015", cfg, "x")
    c = cfg["metrics"]["counting_noise_c"]
    assert precise["target_passed"] == math.ceil((c / 0.015) ** 2) == 609  # (c / cv)^2 spheres, c = 0.37
    heavy = scene_parameters(point, "default_density_scale_100", cfg, "x")
    assert heavy["time_step"] == pytest.approx(base["time_step"] / math.sqrt(10))


@pytest.mark.parametrize("change, message", [
    (lambda f: f.update(reference="finest"), r"'fidelity.reference': value 'finest' is not allowed"),
    (lambda f: f.update(presets=["smoke", "default"]), r"'fidelity.presets'.*must include the reference preset"),
    (lambda f: f.update(presets=["smoke", "quick", "reference"]), r"'fidelity.presets': value 'quick' is not allowed"),
    (lambda f: f["knobs"].update(point="elsewhere"), r"'fidelity.knobs.point': value 'elsewhere'"),
    (lambda f: f["points"]["normal"].update(seed=3), r"'fidelity.points.normal': keys \['seed'\] are not allowed"),
    (lambda f: f.update(seeds=[1]), r"fidelity.seeds"),
    (lambda f: f["knobs"]["values"].update(dt_factor=[1.5]), r"fidelity.knobs.values.dt_factor"),
])
def test_bad_fidelity_config_is_refused_with_the_key(shipped, change, message):
    cfg = copy.deepcopy(shipped)
    change(cfg["fidelity"])
    with pytest.raises(spreadmap_config.ConfigError, match=message):
        spreadmap_config.validate(cfg)


# ---------------------------------------------------------------------------------------------
# errors, noise and cost on synthetic tables with known answers
# ---------------------------------------------------------------------------------------------
def _cases(preset, name, mfr, pd_, cpu, n=100, steps=1000):
    return [{"preset": preset, "name": name, "seed": i, "mfr": m, "pd": p, "status": "ok", "flagged": False,
             "peak_overlap_ratio": 0.01,
             "cpu_time": cpu, "wall_time": 2 * cpu, "n_particles": n, "steps": steps}
            for i, (m, p) in enumerate(zip(mfr, pd_))]


def _table():
    rows = []
    # reference: MFR 0.30 +- 0.01, PD 0.50 +- 0.01 at two points
    rows += _cases("reference", "a", [0.29, 0.30, 0.31], [0.49, 0.50, 0.51], cpu=400)
    rows += _cases("reference", "b", [0.19, 0.20, 0.21], [0.39, 0.40, 0.41], cpu=400)
    # cheap: MFR 20 % high at both points (resolved), PD 1 % high (within noise)
    rows += _cases("cheap", "a", [0.35, 0.36, 0.37], [0.495, 0.505, 0.515], cpu=10)
    rows += _cases("cheap", "b", [0.23, 0.24, 0.25], [0.394, 0.404, 0.414], cpu=10)
    return pd.DataFrame(rows)


def test_preset_errors_match_hand_computed_numbers():
    per_point, presets = study.preset_errors(_table(), "reference")
    cheap = presets.set_index("preset").loc["cheap"]
    assert cheap["mfr_mean_abs_rel_error"] == pytest.approx(0.20)
    assert cheap["pd_mean_abs_rel_error"] == pytest.approx((0.005 / 0.5 + 0.004 / 0.4) / 2)
    # standard error of the difference: sqrt(2 * 0.01^2 / 3)
    se = math.sqrt(2 * 0.01 ** 2 / 3)
    row_a = per_point.set_index(["preset", "name"]).loc[("cheap", "a")]
    assert row_a["mfr_se"] == pytest.approx(se)
    assert row_a["pd_rel_resolution"] == pytest.approx(2 * se / 0.5)
    assert bool(row_a["mfr_resolved"]) and not bool(row_a["pd_resolved"])
    assert cheap["mfr_verdict"].startswith("20.0 % (resolved")
    assert cheap["pd_verdict"].startswith("within noise")
    assert cheap["cost_ratio_to_reference"] == pytest.approx(40.0)
    assert cheap["cpu_s_median"] == 10 and cheap["wall_s_median"] == 20
    assert cheap["particle_steps_per_s"] == pytest.approx(100 * 1000 / 10)
    assert cheap["mfr_seed_cv"] == pytest.approx(np.mean([0.01 / 0.36, 0.01 / 0.24]))
    assert presets.set_index("preset").loc["reference", "mfr_verdict"] == "reference"


def test_failed_and_flagged_cases_are_counted_but_kept_out_of_the_means():
    table = _table()
    extra = pd.DataFrame(_cases("cheap", "a", [0.9], [0.9], cpu=10))
    extra.loc[0, "flagged"] = True
    per_point, presets = study.preset_errors(pd.concat([table, extra], ignore_index=True), "reference")
    row = per_point.set_index(["preset", "name"]).loc[("cheap", "a")]
    assert row["cases"] == 4 and row["usable_cases"] == 3
    assert row["mfr_mean"] == pytest.approx(0.36)
    assert presets.set_index("preset").loc["cheap", "flagged_cases"] == 1


def test_wedged_cases_are_counted_and_the_overlap_column_is_the_free_peak():
    """Where the scene split the peak overlap (a sphere pinned under the blade, or the rest), the
    presets table counts wedged cases (kept: not flagged) and reports the free peak."""
    table = _table()
    table["peak_overlap_free"], table["wedged"] = 0.02, False
    table.loc[table["preset"] == "cheap", "peak_overlap_ratio"] = 0.12
    table.loc[(table["preset"] == "cheap") & (table["name"] == "a"), "wedged"] = True
    _, presets = study.preset_errors(table, "reference")
    cheap = presets.set_index("preset").loc["cheap"]
    assert cheap["wedged_cases"] == 3 and cheap["peak_overlap_max"] == 0.02 and cheap["flagged_cases"] == 0
    assert presets.set_index("preset").loc["reference", "wedged_cases"] == 0
    # tables without the split keep the whole peak and have no wedged column
    _, old = study.preset_errors(_table(), "reference")
    assert "wedged_cases" not in old and old["peak_overlap_max"].tolist() == _table().groupby(
        "preset", sort=False)["peak_overlap_ratio"].max().tolist()


def test_goal_states_met_not_met_and_not_resolved():
    _, presets = study.preset_errors(_table(), "reference")
    # MFR 20 % +- 6.8 % (mean 2 SE over the points), PD 1.0 % +- 3.7 %
    goal = study.goal(presets, "cheap")
    assert not goal["met"] and goal["state"] == "not met"
    assert goal["checks"]["mfr_error"]["state"] == "not met"
    assert goal["checks"]["pd_error"]["state"] == "met"
    assert goal["checks"]["cost_ratio"]["met"] and goal["checks"]["median_cpu_s"]["met"]
    assert study.goal(presets, "cheap", max_rel_error=0.04)["checks"]["pd_error"]["state"] == "not resolved"
    loose = study.goal(presets, "cheap", max_rel_error=0.25)
    assert loose["state"] == "not resolved"
    assert loose["checks"]["pd_error"]["state"] == "met" and loose["checks"]["mfr_error"]["state"] == "not resolved"


def test_noise_floor_chi2_and_seeds_needed():
    _, presets = study.preset_errors(_table(), "reference")
    cheap = presets.set_index("preset").loc["cheap"]
    se = math.sqrt(2 * 0.01 ** 2 / 3)
    # noise floor: sqrt(2/pi) x relative SE, mean over the points
    assert cheap["pd_noise_floor"] == pytest.approx(math.sqrt(2 / math.pi) * np.mean([se / 0.5, se / 0.4]))
    # chi-square over the two points of z = error / SE
    z = np.array([0.005, 0.004]) / se
    assert cheap["pd_chi2"] == pytest.approx(np.sum(z ** 2))
    assert cheap["pd_chi2_p"] == pytest.approx(stats.chi2.sf(np.sum(z ** 2), 2))
    assert cheap["pd_verdict"].startswith("within noise") and cheap["mfr_verdict"].endswith(")")
    assert "resolved" in cheap["mfr_verdict"]
    # seeds for 2 SE = 5 %: (2 / 0.05)^2 (0.01^2 + 0.01^2) / ref^2, median over the points
    assert cheap["pd_seeds_for_5pct"] == pytest.approx(np.median([1600 * 2e-4 / 0.25, 1600 * 2e-4 / 0.16]))


def test_knob_errors_against_the_base_value():
    rows = []
    for value, shift, cpu in ((0.15, 0.0, 20), (0.3, 0.0, 10), (0.45, 0.1, 7)):
        for r in _cases("p", "a", np.array([0.29, 0.30, 0.31]) + shift, [0.49, 0.50, 0.51], cpu=cpu):
            rows.append({**r, "knob": "dt_factor", "value": value, "is_base": value == 0.3})
    knobs = study.knob_errors(pd.DataFrame(rows)).set_index("value")
    assert knobs.loc[0.3, "mfr_verdict"] == "base"
    assert knobs.loc[0.15, "mfr_verdict"].startswith("within noise")
    assert knobs.loc[0.45, "mfr_rel_error"] == pytest.approx(0.1 / 0.3)
    assert knobs.loc[0.15, "cost_ratio_to_base"] == pytest.approx(2.0)


def test_pareto_front_keeps_only_undominated_presets():
    cost = np.array([10.0, 40.0, 20.0, 400.0])
    error = np.array([0.30, 0.05, 0.40, 0.0])
    assert fidelity_plots.pareto_front(cost, error).tolist() == [0, 1, 3]


def test_figures_and_markdown_are_written(tmp_path):
    per_point, presets = study.preset_errors(_table(), "reference")
    paths = fidelity_plots.pareto_figure(presets, "reference", tmp_path / "pareto")
    assert paths["png"].stat().st_size > 1000 and paths["pdf"].stat().st_size > 1000
    assert len(pd.read_csv(paths["csv"])) == 2
    rows = []
    for knob, values in (("dt_factor", (0.15, 0.3)), ("density_scale", (100, 1000, 10000))):
        for value in values:
            for r in _cases("p", "a", [0.29, 0.30, 0.31], [0.49, 0.50, 0.51], cpu=10):
                rows.append({**r, "knob": knob, "value": value, "is_base": value in (0.3, 1000)})
    knobs = study.knob_errors(pd.DataFrame(rows))
    paths = fidelity_plots.knobs_figure(knobs, "default", tmp_path / "knobs")
    assert paths["png"].stat().st_size > 1000
    goals = [study.goal(presets, "cheap")]
    text = study.markdown_summary(presets, per_point, knobs, "reference", goals)
    assert "| cheap |" in text and "within noise" in text and "not met" in text
