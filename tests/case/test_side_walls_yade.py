"""scene.side_walls_adhesive (issue 64): with it false, a sphere-side-wall contact gets no DMT adhesion
on any step; true (the default) the side walls hold a sphere as every contact does, as before. The
YADE run is one small script (yade_scripts/check_side_wall.py) running the template's own
unstick_side_walls on a sphere pressed against a side wall, then pulled off (~2 s); the rest is pure
Python."""
import copy
import json
import math
import subprocess

import pytest
from conftest import ROOT, case_params

from spreadmap.case.identity import case_id, case_scene
from spreadmap.case.launcher import clean_environment, yade_executable

POINT = {"f": 0.3, "d_um": 30.0, "h_um": 65.0, "v_mm_s": 10.0}


@pytest.mark.yade
def test_a_non_adhesive_side_wall_has_no_pull_off_and_an_adhesive_one_dmts(tmp_path):
    """gamma 0.1 J/m^2, R 10 um: adhesive walls pull off at 4 pi gamma R* (R* = R/2, as a sphere on
    a box: tests/case/test_adhesion_yade.py); non-adhesive ones at 0, the contact's first step (made
    as the sphere approaches, the viscous force acting) the dry contact's force to the bit, and its
    adhesionForce 0 from then on."""
    gamma, radius = 0.1, 10e-6
    out = tmp_path / "side_wall.json"
    subprocess.run([yade_executable(), "-n", "-j1", "-x", str(ROOT / "yade_scripts" / "check_side_wall.py"), str(out),
                    str(gamma), str(radius), "7.98e6", "2.1e9", "0.3"],
                   env=clean_environment(), check=True, capture_output=True, timeout=120)
    result = json.loads(out.read_text())
    dmt = 4.0 * math.pi * gamma * (radius / 2.0)
    adhesive, non_adhesive, dry = result["adhesive"], result["non_adhesive"], result["dry"]
    print(f"pull-off / (4 pi gamma R/2): adhesive walls {adhesive['pull_off'] / dmt:.5f}, "
          f"non-adhesive {non_adhesive['pull_off'] / dmt:.5f}")
    assert all(r["separated"] for r in (adhesive, non_adhesive, dry))
    assert adhesive["adhesion_force"] == pytest.approx(dmt, rel=1e-9)
    assert adhesive["pull_off"] == pytest.approx(dmt, rel=0.02)
    assert adhesive["first_force"] == pytest.approx(dry["first_force"] - dmt, rel=1e-9)
    assert non_adhesive["pull_off"] == 0.0 and non_adhesive["adhesion_force"] == 0.0
    assert non_adhesive["first_force"] == pytest.approx(dry["first_force"], rel=1e-12)


def test_the_option_is_in_every_case_and_keys_it(config):
    """Default true (today's scene: the walls stick); false is another case at the same point."""
    assert config["scene"]["side_walls_adhesive"] is True
    assert case_params(config, POINT, "default")["side_walls_adhesive"] is True
    smooth = copy.deepcopy(config)
    smooth["scene"]["side_walls_adhesive"] = False
    cid, params = case_scene(POINT, "default", smooth)
    assert params["side_walls_adhesive"] is False and cid != case_id(POINT, "default", config)


def test_non_adhesive_side_walls_with_rolling_resistance_are_refused(config):
    """The first step of a side-wall contact caps its rolling moment by the adhesive normal force:
    the adhesion cannot be taken off it exactly, so the combination is refused before anything runs."""
    cfg = copy.deepcopy(config)
    cfg["scene"]["side_walls_adhesive"] = False
    cfg["scene"]["rolling_resistance"]["enabled"] = True
    with pytest.raises(ValueError, match="side_walls_adhesive"):
        case_scene(POINT, "default", cfg)


def test_the_scene_unsticks_the_side_walls_only_when_asked_and_adhesive():
    """The runner is in the engines only with side_walls_adhesive false and adhesion on, right after
    the contact law: a default scene runs the engines it ran before issue 64."""
    text = (ROOT / "yade_scripts" / "spreading_case.py").read_text()
    assert 'if P["adhesion_gamma"] > 0.0 and not P["side_walls_adhesive"] else []' in text
    engines = text[text.index("O.engines = ["):text.index("    newton,\n")]
    assert engines.index('label="interactions"') < engines.index('command="unstick_side_walls()"')
