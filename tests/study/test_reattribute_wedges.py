"""tools/reattribute_wedges.py's own parts (no YADE): which flags it re-reads and what counts as the
same simulation. Its re-runs are checked on the study's cases (docs/study/README.md); the rule
itself, and that a raw record carries the parameters the tool re-renders from, by
tests/case/test_stability_yade.py."""
import json

from conftest import script_module

tool = script_module("tools/reattribute_wedges.py")


def test_only_cases_flagged_for_their_overlap_alone_are_chosen():
    assert tool.overlap_flagged_only({"flagged": True, "flag_reason": "peak overlap 0.0948 R > 0.05 R"})
    assert not tool.overlap_flagged_only({"flagged": False, "flag_reason": ""})
    assert not tool.overlap_flagged_only({"flagged": True,
                                          "flag_reason": "peak overlap 0.09 R > 0.05 R; 3 spheres escaped the box"})
    assert not tool.overlap_flagged_only({"flagged": True, "flag_reason": "time step 1.20 x critical"})


def test_the_same_simulation_means_same_status_steps_and_positions():
    run = {"status": "ok", "steps": 100, "snapshots": {"window_end": {"positions": [[0.0, 1.0, 2.0], [1.0, 1.0, 1.0]]}}}
    assert tool.same_simulation(run, json.loads(json.dumps(run))) == ""
    assert "steps" in tool.same_simulation(run, {**run, "steps": 101})
    assert "status" in tool.same_simulation(run, {**run, "status": "blown"})
    moved = json.loads(json.dumps(run))
    moved["snapshots"]["window_end"]["positions"][1][2] = 1.0 + 1e-15
    assert "positions" in tool.same_simulation(run, moved)
    assert "positions" in tool.same_simulation({**run, "snapshots": {}}, {**run, "snapshots": {}})
