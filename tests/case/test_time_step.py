"""The Rayleigh critical step against numbers worked out by hand and against SPEC.md's measured
values (5.3e-8 s at d = 10 um, 2.7e-7 s at d = 50 um, physical density)."""
import pytest

from spreadmap.case.scene import rayleigh_time_step

E, NU, RHO = 2.1e9, 0.3, 7980.0

# pi R sqrt(rho / G) / (0.1631 nu + 0.8766), by hand at d = 10 um (R = 5e-6 m):
#   G = E / (2 (1 + nu)) = 2.1e9 / 2.6 = 8.0769e8 Pa
#   rho / G = 7980 x 2.6 / 2.1e9 = 9.88e-6 s^2/m^2, sqrt = 3.14325e-3 s/m
#   pi R = 1.570796e-5 m; pi R sqrt(rho / G) = 4.93740e-8 s
#   0.1631 x 0.3 + 0.8766 = 0.92553
#   step = 4.93740e-8 / 0.92553 = 5.33466e-8 s
HAND_10_UM = 5.33466e-8


def test_rayleigh_step_by_hand():
    assert rayleigh_time_step(5e-6, RHO, E, NU) == pytest.approx(HAND_10_UM, rel=1e-5)
    # linear in R: d = 50 um is 5x; sqrt in density: x100 is 10x
    assert rayleigh_time_step(25e-6, RHO, E, NU) == pytest.approx(5 * HAND_10_UM, rel=1e-5)
    assert rayleigh_time_step(5e-6, 100 * RHO, E, NU) == pytest.approx(10 * HAND_10_UM, rel=1e-5)


def test_rayleigh_step_matches_spec_numbers():
    """SPEC.md gives two significant figures: within half a unit of the last one."""
    assert rayleigh_time_step(5e-6, RHO, E, NU) == pytest.approx(5.3e-8, abs=0.05e-8)
    assert rayleigh_time_step(25e-6, RHO, E, NU) == pytest.approx(2.7e-7, abs=0.05e-7)
