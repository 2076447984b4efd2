"""The powder model's Bond number and label, against numbers computed by hand: for gamma 0.1 mJ/m^2,
rho 7980 kg/m^3, g 9.81 m/s^2, the pull-off 4 pi gamma R* of two spheres (R* = d/4: pi gamma d) over
one sphere's weight (rho g pi d^3 / 6)."""
import math

import pytest

from spreadmap.case.powder import bond_number, powder_label

MATERIAL = {"density_kg_m3": 7980.0, "gravity_m_s2": 9.81, "surface_energy_j_m2": 1e-4}


@pytest.mark.parametrize("d_um, expected", [(10.0, 76.64), (50.0, 3.066)])
def test_bond_number_is_pull_off_over_weight(d_um, expected):
    d = d_um * 1e-6
    pull_off = math.pi * 1e-4 * d                       # 4 pi gamma (d/4)
    weight = 7980.0 * 9.81 * math.pi * d ** 3 / 6.0
    assert bond_number(1e-4, 7980.0, 9.81, d) == pytest.approx(pull_off / weight, rel=1e-12)
    assert bond_number(1e-4, 7980.0, 9.81, d) == pytest.approx(expected, rel=1e-3)  # SPEC: tens at 10 um, a few at 50


def test_the_label_names_the_model_and_its_bond_numbers():
    label = powder_label({"material": MATERIAL, "ranges": {"d_um": {"min": 10, "max": 50}}})
    assert label.startswith("adhesive spheres (DMT, surface energy 0.1 mJ/m^2")
    assert "77 at d = 10 um" in label and "3.1 at 50 um" in label
    assert powder_label({"material": {**MATERIAL, "surface_energy_j_m2": 0.0}}) == "dry spheres (no adhesion)"
    assert powder_label({"material": {"density_kg_m3": 7980.0, "gravity_m_s2": 9.81}}) == "dry spheres (no adhesion)"


def test_the_label_names_a_size_distribution_and_not_one_size(config):
    import copy

    from spreadmap.case.powder import powder_label

    one = copy.deepcopy(config)
    one["material"]["size_distribution"] = {"span": 0.0, "tails": [0.05, 0.95]}
    assert "sizes" not in powder_label(one)
    wide = copy.deepcopy(config)
    wide["material"]["size_distribution"] = {"span": 1.0, "tails": [0.05, 0.95]}
    assert powder_label(wide) == powder_label(one) + ", sizes log-normal by volume (span 1, cut at D5-D95; d is the D50)"
