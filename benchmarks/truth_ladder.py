#!/usr/bin/env python
"""The fidelity ladder toward the stiff limit under adhesion (issue 64): how far each density scale
is from the stiffest level measured, at points that span the Bond number and h/d.

A density scale S (every mass x S, the surface energy x S with it) is the real-density powder at
Young's modulus E / S: the ladder x1000 (the shipped `default`), x100, x10, x1 (the config's E at
the real density) walks toward the stiff limit. Two more arms:
  x1_E10      density x1 at E / 10 with the config's surface energy: the same powder as x10 (whose
              applied surface energy is 10 gamma, its masses x10) written in other units. Equal to x10
              within noise, or a dimensional parameter of the scene is not scaled.
  x1_316L     density x1 at 316L's own Young's modulus (`--young-316l`, 193 GPa by default; source in
              docs/truth/README.md): one more step toward the stiff limit at ~9.6x the CPU of x1.
  x1000_walls_dry  the shipped x1000 with the slice's side walls not adhesive (scene.side_walls_adhesive
              false): the walls' artefact (a real bed has no walls to stick to).
  x1000_p<p>  density x1000 with the applied surface energy gamma x 1000^p instead of the shipped
              Bond-keeping gamma x 1000 (p = 1): p = 0.6 keeps x1's work of separating a contact
              (gamma S (1/S)^(2/5)); the rules pre-registered in docs/truth/README.md.
Every arm is the shipped `default` preset and scene with only these changed. Cases run two at a
time (one per core), each in its own process so its CPU time is its own, in the order of
`PRIORITY` (the cheap rungs and the cheap points' whole ladder first), every finished case appended
at once to --csv (a run cut short keeps what it finished; a re-run skips what is there).

    PYTHONPATH=. .venv/bin/python benchmarks/truth_ladder.py --csv docs/truth/ladder_cases.csv \
        --summary docs/truth/ladder_summary.md --keep /work/runs/ladder_cases
"""
from __future__ import annotations

import argparse
import copy
import re
from pathlib import Path

import numpy as np

from spreadlab.experiments.arms import add_arguments, arm_summary, number, run_arm_case, run_study
from spreadmap import config as spreadmap_config

ROOT = Path(__file__).resolve().parent.parent
# f, d_um, h_um, v_mm_s: Bond number 3.8 to ~60 (d 45 to 11 um), h/d 1.3 to 6.8, a slow and a fast blade
POINTS = {"coarse": (0.30, 45.0, 60.0, 10.0), "medium": (0.30, 30.0, 60.0, 10.0), "fine": (0.30, 15.0, 60.0, 10.0),
          "slow": (0.45, 40.0, 70.0, 5.0), "corner": (0.20, 11.0, 75.0, 15.0)}
# arm -> (density scale, Young's modulus: None = the config's, a number = times the config's, "316L" = --young-316l)
ARMS = {"x1000": (1000.0, None), "x100": (100.0, None), "x10": (10.0, None), "x1": (1.0, None),
        "x1_E10": (1.0, 0.1), "x1_316L": (1.0, "316L"), "x1000_p0.8": (1000.0, None), "x1000_p0.6": (1000.0, None),
        "x1000_walls_dry": (1000.0, None)}
DEFAULT_ARMS = ["x1000", "x100", "x10", "x1", "x1_E10"]
REFERENCE_ARM = "x1"
# the order cases run in (a run cut short has whole ladders at the cheap points first); cases of the
# asked arms, points and seeds not named here run last, cheapest first
PRIORITY = ([("coarse", a) for a in ("x1000", "x100", "x10", "x1_E10", "x1")]
            + [("medium", a) for a in ("x1000", "x100", "x10", "x1")]
            + [(p, a) for p in ("coarse", "medium", "fine") for a in ("x1000_p0.8", "x1000_p0.6")]
            + [("fine", a) for a in ("x1000", "x1000_walls_dry", "x100", "x10", "x1")]
            + [("slow", a) for a in ("x1000", "x100", "x10", "x1")]
            + [("corner", "x1000"), ("corner", "x100"), ("corner", "x10"), ("medium", "x1_316L"), ("corner", "x1")])
COLUMNS = ("arm", "point", "seed", "case_id", "f", "d_um", "h_um", "v_mm_s", "young_pa", "surface_energy",
           "density_scale", "bond_number", "status", "flagged", "flag_reason", "regime", "mfr", "pd", "mfr_sd",
           "pd_sd", "n_passed", "layer_fill", "coverage", "thickness_ratio", "roughness_d", "flow_trend_z",
           "n_particles", "steps", "time_step", "peak_overlap_ratio", "cpu_time", "wall_time", "jam_events",
           "jam_events_per_mm")


def surface_energy_exponent(arm: str) -> float | None:
    """p of an arm `x<S>_p<p>` (the applied surface energy gamma x S^p), None for the others."""
    match = re.fullmatch(r"x[0-9.]+_p([0-9.]+)", arm)
    return float(match.group(1)) if match else None


def add_exponent_arm(arm: str) -> str:
    """Register an arm `x1000_p<p>` (any p, e.g. the exponent fitted between the rules); the arm's name."""
    if surface_energy_exponent(arm) is None or not arm.startswith("x1000_"):
        raise argparse.ArgumentTypeError(f"{arm!r}: an exponent arm is x1000_p<p>, e.g. x1000_p0.73")
    ARMS.setdefault(arm, (1000.0, None))
    return arm


def arm_config(base: dict, arm: str, young_316l: float) -> tuple[dict, str]:
    """The config of an arm and the name of its preset (`default`, or `default_density_scale_<s>`)."""
    scale, young = ARMS[arm]
    cfg = copy.deepcopy(base)
    if arm == "x1000_walls_dry":
        cfg["scene"]["side_walls_adhesive"] = False
    exponent = surface_energy_exponent(arm)
    if exponent is not None:  # the scene applies gamma x S: gamma x S^p is the config's gamma x S^(p - 1)
        cfg["material"]["surface_energy_j_m2"] = float(base["material"]["surface_energy_j_m2"]) * scale ** (exponent - 1.0)
    if young == "316L":
        cfg["material"]["young_pa"] = float(young_316l)
    elif young is not None:
        cfg["material"]["young_pa"] = float(base["material"]["young_pa"]) * young
    name = "default" if scale == cfg["presets"]["default"]["density_scale"] else f"default_density_scale_{scale:g}"
    cfg["presets"][name] = {**cfg["presets"]["default"], "density_scale": scale}
    return cfg, name


def order(job: tuple[str, str, int]) -> tuple:
    """Sort key of (arm, point, seed): PRIORITY's place, then the seed."""
    arm, point, seed = job
    try:
        return (PRIORITY.index((point, arm)), seed)
    except ValueError:
        return (len(PRIORITY), -ARMS[arm][0], -POINTS[point][1], seed)


def run_one(job: dict) -> dict:
    """Render, run and measure one case in its own folder; the row of the cases table."""
    cfg, preset = arm_config(job["base"], job["arm"], job["young_316l"])
    f, d, h, v = POINTS[job["point"]]
    row, params = run_arm_case(cfg, preset, {"f": f, "d_um": d, "h_um": h, "v_mm_s": v}, job["seed"], job["keep"], COLUMNS)
    row.update({"arm": job["arm"], "point": job["point"], "surface_energy": params["surface_energy"],
                "density_scale": params["density_scale"], "young_pa": params["young"],
                "time_step": params["time_step"]})
    return row


def summary(rows: list[dict]) -> str:
    """Per point and arm: MFR, PD and coverage (mean of the seeds ± SE from their spread), the
    difference from the stiffest arm measured (x1) with its SE, the CPU per case."""
    return arm_summary(rows, POINTS, ARMS, REFERENCE_ARM,
                       extra={"Bond": lambda ran: f"{np.nanmedian([number(r['bond_number']) for r in ran]):.1f}"})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--young-316l", type=float, default=193e9, help="x1_316L's Young's modulus, Pa (default 193e9)")
    ap.add_argument("--exponent-arm", type=add_exponent_arm, action="append", default=[],
                    help="add an arm x1000_p<p> (the fitted rule's exponent); run it with --arms")
    ap.parse_known_args()  # registers the exponent arms before --arms lists its choices
    add_arguments(ap, POINTS, ARMS, DEFAULT_ARMS, "/tmp/truth_ladder")
    ap.set_defaults(seeds=[1, 2, 3])
    args = ap.parse_args()
    base = spreadmap_config.load(args.config)
    run_study(args, order, lambda a, p, s: {"base": base, "arm": a, "point": p, "seed": s, "keep": args.keep,
                                            "young_316l": args.young_316l},
              run_one, COLUMNS, summary, extra=lambda row: f"Bo {number(row.get('bond_number')):.1f}")


if __name__ == "__main__":
    main()
