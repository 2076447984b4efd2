"""A rendered case is self-contained, readable, and re-run by hand with `yade -n -x` it
reproduces its recorded result."""
import ast
import json
import subprocess

import pytest
from conftest import case_params, run_scene

from spreadmap.case.launcher import clean_environment, yade_executable
from spreadmap.case.render import render, template_sha256
from spreadmap.metrics import case_metrics


def test_rendered_script_embeds_the_parameters(config):
    params = case_params(config, {"f": 0.25, "d_um": 40.0, "h_um": 60.0, "v_mm_s": 7.0})
    text = render(params)
    ast.parse(text)  # valid Python
    assert f"# --- case parameters of {params['case_id']} (rendered by spreadmap) ---" in text
    block = text[text.index("PARAMS = "):text.index("# --- end of case parameters ---")]
    assert ast.literal_eval(block[len("PARAMS = "):]) == params
    assert text.count("PARAMS = {") == 1


def test_render_refuses_parameters_derived_for_another_scene(config):
    params = {**case_params(config, {"f": 0.25, "d_um": 40.0, "h_um": 60.0, "v_mm_s": 7.0}), "scene_sha256": "0" * 16}
    with pytest.raises(ValueError, match="another version"):
        render(params)
    assert len(template_sha256()) == 16


@pytest.mark.yade
def test_rerun_by_hand_reproduces_the_recorded_result(config, tmp_path):
    params = case_params(config, {"f": 0.3, "d_um": 40.0, "h_um": 65.0, "v_mm_s": 10.0})
    result, raw = run_scene(params, tmp_path)
    assert result["outcome"] == "ok"
    by_hand = tmp_path / "by_hand.json"
    subprocess.run([yade_executable(), "-n", "-j1", "-x", str(tmp_path / "case.py"), str(by_hand)],
                   env=clean_environment(), check=True, capture_output=True, timeout=300)
    again = json.loads(by_hand.read_text())
    first, second = (case_metrics(r, config["regime"], config["stability"], config["metrics"]) for r in (raw, again))
    assert (first["mfr"], first["pd"], first["steps"]) == (second["mfr"], second["pd"], second["steps"])
    assert raw["snapshots"]["window_end"]["positions"] == again["snapshots"]["window_end"]["positions"]


@pytest.mark.yade
def test_the_run_ends_in_the_step_that_ends_it(config, tmp_path):
    """The end state is taken inside the step that ends the run, and nothing runs after it: with
    the monitor due in that very step, it does not record the end twice, and the step counters are
    those after the ending step (YADE's thread may still be completing it when O.wait() returns)."""
    params = case_params(config, {"f": 0.3, "d_um": 45.0, "h_um": 65.0, "v_mm_s": 12.0},
                         control_every=100, monitor_every=100)
    result, raw = run_scene(params, tmp_path)
    assert result["outcome"] == "ok"
    end = raw["snapshots"]["window_end"]
    times = [t for t, _, _ in raw["behind_series"]]
    assert times[-1] == end["time"] and times[-2] < times[-1]
    assert raw["steps"] == end["iter"] + 1 and raw["steps"] % 100 == 1
    assert raw["simulated_time"] == end["time"] + raw["time_step"]
