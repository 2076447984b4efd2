"""Bad configuration is refused with the key, the value and what is allowed; nothing is written."""
import copy
import warnings

import pytest
import yaml
from conftest import ROOT, make_workflow, snakemake

from spreadmap.config import ConfigError, validate


@pytest.fixture()
def raw_config():
    return yaml.safe_load((ROOT / "config.yaml").read_text())


@pytest.mark.parametrize("change,message", [
    (lambda c: c["material"].update(poisson=0.6), r"'material\.poisson': value 0\.6 .* must be < 0\.5"),
    (lambda c: c["presets"]["default"].update(width_d="five"), r"'presets\.default\.width_d': value 'five' .* of type number"),
    (lambda c: c.update(preset="fastest"),
     r"'preset': value 'fastest' .* one of the presets defined: \['default', 'fast', 'reference', 'smoke'\]"),
    (lambda c: c.update(bogus=1), r"unknown config key\(s\) \['bogus'\] at the top level"),
    (lambda c: c["sweeps"]["lds"].update(partitions=[8, 1]), r"'sweeps\.lds\.partitions\[1\]': value 1 .* must be >= 2"),
    (lambda c: c["ranges"].update(d_um={"min": 50, "max": 10}), r"'ranges\.d_um': min 50 must be below max 10"),
    (lambda c: c["points"]["named"]["normal"].update(preset="nope"), r"'points\.named\.normal\.preset': value 'nope'"),
    (lambda c: c["presets"]["smoke"].pop("dt_factor"), r"'presets\.smoke': 'dt_factor' is a required property"),
    (lambda c: c["presets"]["smoke"].update(dt_factor=1.5), r"'presets\.smoke\.dt_factor': value 1\.5 .* must be <= 1"),
    (lambda c: c.update(noise_calibration=[{"h_over_d_below": 2, "factor": -1}]),
     r"'noise_calibration\[0\]\.factor': value -1 .* must be > 0"),
    (lambda c: c.update(noise_calibration=[{"factor": 0.6}]),
     r"'noise_calibration\[0\]': .* must be a mapping with at least one of the keys \['h_over_d_below', 'h_over_d_from'\]"),
    (lambda c: c.update(noise_calibration=[{"h_over_d_from": 3, "h_over_d_below": 2, "factor": 0.6}]),
     r"'noise_calibration\[0\]': h_over_d_from 3 must be below h_over_d_below 2 \(the region is empty\)"),
    # the fitted noise law sets MFR's and PD's SDs: a hand band beside it may scale only the others
    (lambda c: c.update(noise_calibration=[{"h_over_d_below": 2, "factor": 1.37}]),
     r"'noise_calibration': noise_calibration\[0\] scales \['mfr', 'pd'\], whose noise SDs noise_model sets "
     r"\(a region without `targets` scales every target\)"),
    (lambda c: c.update(noise_calibration=[{"h_over_d_from": 3, "factor": 0.61, "targets": ["pd", "coverage"]}]),
     r"'noise_calibration': noise_calibration\[0\] scales \['pd'\]"),
    (lambda c: c["noise_model"]["mfr"].update(n_exponent=0.5), r"'noise_model\.mfr\.n_exponent': value 0\.5 .* must be <= 0"),
    (lambda c: c["noise_model"].pop("pd"), r"'noise_model': 'pd' is a required property"),
])
def test_bad_values_are_refused_with_the_key_named(raw_config, change, message):
    change(raw_config)
    with pytest.raises(ConfigError, match=message):
        validate(copy.deepcopy(raw_config))


def test_the_shipped_config_is_valid_and_defaults_are_filled(raw_config):
    cfg = validate(copy.deepcopy(raw_config))
    assert "settle_time_factor" not in raw_config["scene"]
    assert cfg["scene"]["settle_time_factor"] == 4  # a default from the schema


@pytest.mark.parametrize("overrides,message", [
    ({"preset": "fastest"}, "config key 'preset': value 'fastest' is not allowed"),
    ({"presets": {"default": {"time_step_s": 1e-6, "density_scale": 1}}},
     "presets.default.time_step_s': value 1e-06 s is above the Rayleigh critical step"),
])
def test_workflow_refuses_bad_config_before_anything_runs(tmp_path, overrides, message):
    wf = make_workflow(tmp_path, overrides)
    result = snakemake(wf, "-n")
    assert result.returncode != 0
    assert message in result.stdout + result.stderr
    assert not (wf / "results").exists()


@pytest.mark.parametrize("text,written", [("2.1e9", "2.1e+9"), ("1e-6", "1.0e-6")])
def test_a_number_yaml_reads_as_a_string_is_explained(raw_config, text, written):
    """PyYAML (YAML 1.1) reads 2.1e9 and 1e-6 as strings; the message names the key and says how
    to write the number so that YAML reads it as one (checked by reading that back)."""
    raw_config["material"]["young_pa"] = yaml.safe_load(f"young_pa: {text}")["young_pa"]
    assert raw_config["material"]["young_pa"] == text  # what YAML really does
    with pytest.raises(ConfigError) as error:
        validate(copy.deepcopy(raw_config))
    message = str(error.value)
    assert message == (f"config key 'material.young_pa': value '{text}' is not allowed; it must be of type number "
                       f"(YAML 1.1 reads {text} as a string: write {written})")
    assert "\n" not in message and isinstance(yaml.safe_load(f"x: {written}")["x"], float)


@pytest.mark.parametrize("change,key", [
    (lambda c: c["scene"].update(seed=-1), r"scene\.seed"),
    (lambda c: c["fidelity"].update(seeds=[1, -1]), r"fidelity\.seeds\[1\]"),
    (lambda c: c["fidelity"]["knobs"].update(seeds=[-2, 1]), r"fidelity\.knobs\.seeds\[0\]"),
    (lambda c: c["points"]["named"]["normal"].update(seed=-1), r"points\.named\.normal\.seed"),
])
def test_a_negative_packing_seed_is_refused(raw_config, change, key):
    """YADE's makeCloud seeds from the clock for a negative seed (not reproducible); 0 and up are
    reproducible in this build (tests/case/test_packing_seed_yade.py)."""
    change(raw_config)
    with pytest.raises(ConfigError, match=key + r"': value -\d is not allowed; it must be >= 0"):
        validate(copy.deepcopy(raw_config))


def test_the_study_rules_old_section_name_is_read_with_a_warning_naming_both(raw_config):
    """`convergence:` (before the rename) is read as `study_rule:`, with a warning naming the old
    and the new key; given under both names the config is refused."""
    cfg = copy.deepcopy(raw_config)
    cfg["convergence"] = dict(cfg.pop("study_rule"), tolerance=0.0125)
    with pytest.warns(FutureWarning, match=r"'convergence:' is deprecated, read as 'study_rule:'.*`converge:`"):
        out = validate(cfg)
    assert "convergence" not in out and out["study_rule"]["tolerance"] == 0.0125
    both = copy.deepcopy(raw_config)
    both["convergence"] = {"tolerance": 0.01}
    with pytest.raises(ConfigError, match=r"both 'convergence:' and 'study_rule:'.*keep 'study_rule:' only"):
        validate(both)


@pytest.mark.parametrize("path", sorted(p.relative_to(ROOT) for p in (ROOT / "docs").rglob("config.yaml")))
def test_every_published_config_still_loads(path):
    """The configs published under docs/ (written before the rename, with `convergence:`) load,
    their study rule's section under its new name, unchanged."""
    raw = yaml.safe_load((ROOT / path).read_text())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        cfg = validate(copy.deepcopy(raw))
    old = raw.get("convergence", raw.get("study_rule"))
    assert old is not None
    for key, value in old.items():  # the schema may fill defaults inside (e.g. the floors of mean, std)
        got = cfg["study_rule"][key]
        assert ({k: got[k] for k in value} if isinstance(value, dict) else got) == value, key
