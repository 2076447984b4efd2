"""benchmarks/truth_ladder.py's arms (issue 64) are the physics they claim, checked on the scene
parameters the product renders (no YADE run): x1_E10 is x10 in other units, the exponent arms
apply gamma x S^p, 316L's arm changes E alone."""
from __future__ import annotations

import math

import pytest
from conftest import ROOT, script_module

from spreadmap import config as spreadmap_config
from spreadmap.case.identity import case_scene

ladder = script_module("benchmarks/truth_ladder.py")
POINT = {"f": 0.3, "d_um": 45.0, "h_um": 60.0, "v_mm_s": 10.0}


@pytest.fixture(scope="module")
def base():
    return spreadmap_config.load(ROOT / "config.yaml")


def params(base, arm):
    cfg, preset = ladder.arm_config(base, arm, 193e9)
    return case_scene(POINT, preset, cfg, 1)[1]


def test_x1_at_e_over_10_is_x10_in_other_units(base):
    x10, x1e = params(base, "x10"), params(base, "x1_E10")
    # every mass / 10, every force law's stiffness / 10, the applied surface energy / 10: a = F / m unchanged
    assert x10["density"] / x1e["density"] == pytest.approx(10.0, rel=1e-12)
    assert x10["young"] / x1e["young"] == pytest.approx(10.0, rel=1e-12)
    assert x10["adhesion_gamma"] / x1e["adhesion_gamma"] == pytest.approx(10.0, rel=1e-12)
    assert x10["rolling_stiffness"] / x1e["rolling_stiffness"] == pytest.approx(10.0, rel=1e-12)  # a stiffness
    # every other parameter the scene receives is the same: the same step (it scales as sqrt(rho / E)),
    # the same contact time, geometry, counts and thresholds (a threshold in absolute energy or force
    # would differ here)
    differ = {"density", "young", "adhesion_gamma", "density_scale", "surface_energy", "case_id", "scene_sha256",
              "preset", "estimated_steps", "timeout_s", "rolling_stiffness"}
    for key in sorted(set(x10) - differ):
        if isinstance(x10[key], float):
            assert x1e[key] == pytest.approx(x10[key], rel=1e-12), key
        else:
            assert x1e[key] == x10[key], key


def test_exponent_arms_apply_gamma_times_s_to_the_p(base):
    gamma = float(base["material"]["surface_energy_j_m2"])
    assert params(base, "x1000")["adhesion_gamma"] == pytest.approx(gamma * 1000.0, rel=1e-12)
    for p in (0.8, 0.6):
        assert params(base, f"x1000_p{p}")["adhesion_gamma"] == pytest.approx(gamma * 1000.0 ** p, rel=1e-12)
    # p = 0.6 keeps x1's work of separation W ~ gamma_eff^(5/3) (E/S)^(-2/3) (gamma_eff = applied / S)
    work = lambda applied, s: (applied / s) ** (5 / 3) * (2.1e9 / s) ** (-2 / 3)  # noqa: E731
    assert work(gamma * 1000.0 ** 0.6, 1000.0) == pytest.approx(work(gamma, 1.0), rel=1e-9)
    ladder.add_exponent_arm("x1000_p0.73")
    assert params(base, "x1000_p0.73")["adhesion_gamma"] == pytest.approx(gamma * 1000.0 ** 0.73, rel=1e-12)


def test_316l_arm_changes_the_modulus_alone(base):
    x1, steel = params(base, "x1"), params(base, "x1_316L")
    assert steel["young"] == 193e9 and x1["young"] == pytest.approx(2.1e9)
    assert steel["density"] == x1["density"] and steel["adhesion_gamma"] == x1["adhesion_gamma"]
    # the critical step ~ sqrt(rho / E): 316L's is sqrt(193 / 2.1) = 9.59x shorter
    assert x1["time_step"] / steel["time_step"] == pytest.approx(math.sqrt(193e9 / 2.1e9), rel=1e-9)


def test_a_bad_exponent_arm_is_refused():
    with pytest.raises(Exception, match="x1000_p"):
        ladder.add_exponent_arm("x100_q0.5")


def test_the_walls_arm_changes_the_walls_alone(base):
    shipped, dry_walls = params(base, "x1000"), params(base, "x1000_walls_dry")
    assert shipped["side_walls_adhesive"] is True and dry_walls["side_walls_adhesive"] is False
    assert {k for k in shipped if shipped[k] != dry_walls[k]} == {"side_walls_adhesive", "case_id"}
