#!/usr/bin/env python
"""Re-evaluate a published loop's last step under other noise calibrations: would it have stopped?

    .venv/bin/python tools/recheck_stop.py [--published docs/study] [--calibration FILE.yaml ...]

The loop's last step (converge/steps/step_N.json, after N cases) is decided again from the
published cases table (cases_converge.csv, in the loop's run order) and the step before it, with
the stated noise SDs, with the published config's `noise_calibration`, and with that of each
`--calibration` file (a YAML file with a `noise_calibration` key, a `noise_model` key, or both, e.g.
a config.yaml: MFR's and PD's SDs from the fitted law, spreadmap.noise_law.apply). Prints, per
calibration and target, the CV RMSE, the noise it is held against, the threshold and their ratio
(below 1: the criterion holds), and whether every criterion holds. The GP is fitted anew each
time (one restart, as in the loop), so the RMSE differs from the step's own by the fit's noise.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd
import yaml

from spreadlab.recheck import redecide
from spreadmap import config as spreadmap_config
from spreadmap.loop.stepper import step_number
from spreadmap.noise_law.apply import case_noise, check_sections


def last_two_steps(steps_dir: Path) -> tuple[dict, dict]:
    paths = sorted(steps_dir.glob("step_*.json"), key=step_number)
    if len(paths) < 2:
        raise ValueError(f"{steps_dir}: fewer than two loop steps")
    return tuple(json.loads(p.read_text()) for p in paths[-2:])


def recheck(table: pd.DataFrame, cfg: dict, last: dict, previous: dict, calibration: list,
            noise_model: dict | None = None) -> dict:
    """The last step decided again with the cases' noise SDs calibrated by `calibration` (and MFR's
    and PD's from `noise_model`, a fitted law, where given)."""
    n = int(last["n"])
    if len(table) != n:
        raise ValueError(f"the last step is after {n} cases; the cases table has {len(table)} rows")
    noisy = case_noise(table, noise_model, calibration, cfg["metrics"]["counting_noise_c"])
    return redecide(noisy, n, cfg, previous)


def cv_lines(name: str, record: dict) -> list[str]:
    criteria = record["criteria"].get("at_this_batch", record["criteria"])
    lines = [f"{name}: {'stops' if record['stop'] else 'goes on'} ({record['reason']})"]
    for target, cv in criteria["cv_rmse"]["targets"].items():
        lines.append(f"  {target}: CV RMSE {cv['rmse']:.4f}, noise {cv['noise_sd']:.4f}, threshold {cv['threshold']:.4f}"
                     f" -> {cv['ratio']:.2f}x the threshold")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--published", default=str(Path(__file__).resolve().parents[1] / "docs" / "study"))
    parser.add_argument("--calibration", nargs="*", default=[],
                        help="YAML files with a noise_calibration key, a noise_model key or both")
    args = parser.parse_args(argv)
    published = Path(args.published)
    try:
        cfg = spreadmap_config.load(published / "config.yaml")
        table = pd.read_csv(published / "cases_converge.csv")
        previous, last = last_two_steps(published / "converge" / "steps")
        variants = [("stated SDs", [], None), (f"{published / 'config.yaml'}", cfg["noise_calibration"], None)]
        for path in args.calibration:
            loaded = yaml.safe_load(Path(path).read_text()) or {}
            calibration, noise_model = loaded.get("noise_calibration"), loaded.get("noise_model")
            if calibration is None and noise_model is None:
                raise ValueError(f"{path}: no noise_calibration key (nor a noise_model)")
            calibration = spreadmap_config.validate({**cfg, "noise_calibration": calibration or []})["noise_calibration"]
            check_sections(noise_model, calibration)
            variants.append((path, calibration, noise_model))
    except (OSError, ValueError, spreadmap_config.ConfigError) as error:
        print(f"recheck_stop: {error}", file=sys.stderr)
        return 2
    print(f"the loop's step after {last['n']} cases (it {'stopped' if last['stop'] else 'went on'}), decided again:")
    for name, calibration, noise_model in variants:
        label = f"{name} {calibration}" + (f" noise_model {noise_model}" if noise_model else "")
        print("\n".join(cv_lines(label, recheck(table, cfg, last, previous, calibration, noise_model))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
