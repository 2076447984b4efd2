#!/usr/bin/env python
"""What density scaling costs in accuracy once adhesion is on, and what adhesion costs per case
(issue 49).

Arms (each the shipped `default` preset and scene, one thing changed):
  dry_x1000     surface energy 0 (the seed study's cohesionless spheres), density x1000 (as shipped before);
  adh_x1000     surface energy `--gamma` (the real powder's), density x1000: the cohesive default;
  adh_x100      the same at density x100 (a 3.2x smaller step: ~3.2x the CPU);
  adh_x10       the same at density x10 (~10x the CPU): the reference of this study;
  adh_energy_x1000  density x1000 with the surface energy x (10/1000)^(2/5) = 0.158: the x10 scene's
                work of separating a contact, not its Bond number (below);
  adh_roll_x1000  adh_x1000 with YADE's rolling resistance on, eta = --rolling-eta (the cap of the
                rolling moment, eta x mean radius x |Fn|; 0.25 is mu_r = 0.5 of a CDT/EPSD-style law
                for equal spheres, the value Bouabbou & Vaudreuil calibrated for SS316L).
The scene multiplies the surface energy by the density scale, so every arm has the real powder's
Bond number; what scaling changes is the stiffness against the weight and the adhesion (see
docs/adhesion). Points: fine / medium / coarse (d 15 / 30 / 45 um at f 0.3, h 60 um, v 10 mm/s),
each with --seeds packing seeds. Cases run two at a time (one per core), each in its own process so
that its CPU time is its own, cheapest first; every finished case is appended to --csv at once (a
run cut short keeps what it finished; a re-run skips the cases already in --csv).

    .venv/bin/python benchmarks/adhesion_scaling.py --csv docs/adhesion/scaling_cases.csv \
        --summary docs/adhesion/scaling_summary.md --keep /tmp/adhesion_scaling
"""
from __future__ import annotations

import argparse
import copy
import json
from pathlib import Path

import numpy as np

from spreadlab.experiments.arms import add_arguments, arm_summary, number, run_arm_case, run_study
from spreadmap import config as spreadmap_config
from spreadmap.files import write_text_atomically

ROOT = Path(__file__).resolve().parent.parent
POINTS = {"fine": (0.30, 15.0, 60.0, 10.0), "medium": (0.30, 30.0, 60.0, 10.0), "coarse": (0.30, 45.0, 60.0, 10.0)}
ARMS = {"dry_x1000": (False, 1000.0), "adh_x1000": (True, 1000.0), "adh_x100": (True, 100.0), "adh_x10": (True, 10.0),
        "adh_roll_x1000": (True, 1000.0), "adh_energy_x1000": (True, 1000.0)}
# adh_energy_x1000: density x1000 with the surface energy lowered so that the work of pulling a
# contact apart (~ pull-off x equilibrium overlap, ~ gamma^(5/3) S^(2/3) at stiffness E/S) is the
# x10 scene's: gamma x (10 / 1000)^(2/5) = 0.158 gamma (its Bond number 0.158x the real one)
ENERGY_MATCH = (10.0 / 1000.0) ** 0.4
DEFAULT_ARMS = ["dry_x1000", "adh_x1000", "adh_x100", "adh_x10"]
REFERENCE_ARM = "adh_x10"
COLUMNS = ("arm", "point", "seed", "case_id", "f", "d_um", "h_um", "v_mm_s", "surface_energy", "density_scale",
           "bond_number", "status", "flagged", "flag_reason", "regime", "mfr", "pd", "mfr_sd", "pd_sd", "n_passed",
           "layer_fill", "coverage", "thickness_ratio", "roughness_d", "flow_trend_z", "n_particles", "steps",
           "peak_overlap_ratio", "cpu_time", "wall_time")


def arm_config(base: dict, arm: str, gamma: float, rolling_eta: float = 0.25) -> tuple[dict, str]:
    """The config of an arm and the name of its preset (`default`, or `default_density_scale_<s>`)."""
    adhesive, scale = ARMS[arm]
    cfg = copy.deepcopy(base)
    cfg["material"]["surface_energy_j_m2"] = (gamma * (ENERGY_MATCH if arm == "adh_energy_x1000" else 1.0)
                                              if adhesive else 0.0)
    if arm == "adh_roll_x1000":
        cfg["scene"]["rolling_resistance"] = {**cfg["scene"].get("rolling_resistance", {}), "enabled": True,
                                              "rolling_friction": rolling_eta}
    name = "default" if scale == cfg["presets"]["default"]["density_scale"] else f"default_density_scale_{scale:g}"
    cfg["presets"][name] = {**cfg["presets"]["default"], "density_scale": scale}
    return cfg, name


def run_one(job: dict) -> dict:
    """Render, run and measure one case in its own folder; the row of the cases table."""
    cfg, preset = arm_config(job["base"], job["arm"], job["gamma"], job["rolling_eta"])
    f, d, h, v = POINTS[job["point"]]
    row, params = run_arm_case(cfg, preset, {"f": f, "d_um": d, "h_um": h, "v_mm_s": v}, job["seed"], job["keep"], COLUMNS)
    row.update({"arm": job["arm"], "point": job["point"], "surface_energy": params["surface_energy"],
                "density_scale": params["density_scale"]})
    return row


def summary(rows: list[dict]) -> str:
    """Per point and arm: MFR, PD and the layer's coverage (mean of the seeds, SE from their
    spread), the difference from the reference arm with its SE, and the CPU per case."""
    return arm_summary(rows, POINTS, ARMS, REFERENCE_ARM,
                       extra={"Bond": lambda ran: f"{np.nanmedian([number(r['bond_number']) for r in ran]):.2f}"})


def density_correction(rows: list[dict]) -> dict:
    """The factor from density x1000 to x10 under adhesion, per target, with its SD at a point not
    run: spreadlab.paired_factor on the arms' pairs (a point and a seed at both arms)."""
    import pandas as pd

    from spreadlab.paired_factor import config_block, correction

    table = pd.DataFrame(rows).rename(columns={"arm": "preset", "point": "name"})
    for column in ("seed", "f", "d_um", "h_um", "v_mm_s", "mfr", "pd", "mfr_sd", "pd_sd", "cpu_time"):
        table[column] = pd.to_numeric(table[column], errors="coerce")
    table["flagged"] = table["flagged"].astype(str) == "True"
    result = correction(table, preset="adh_x1000", reference=REFERENCE_ARM)
    block = config_block(result, source="docs/adhesion", floor="rough")
    block.update({"preset": "default", "reference": "density x10"})
    return {"result": result, "config_block": block}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default=str(ROOT / "config.yaml"))
    ap.add_argument("--gamma", type=float, default=1e-4, help="the real surface energy, J/m^2 (default 1e-4)")
    ap.add_argument("--rolling-eta", type=float, default=0.25, help="adh_roll_x1000: YADE's eta (default 0.25)")
    ap.add_argument("--correction", help="write the x1000 -> x10 factor (JSON) here")
    add_arguments(ap, POINTS, ARMS, DEFAULT_ARMS, "/tmp/adhesion_scaling")
    args = ap.parse_args()
    base = spreadmap_config.load(args.config)
    # cheapest first: coarse before fine, x1000 before x10
    rows = run_study(args, lambda j: (-ARMS[j[0]][1], -POINTS[j[1]][1], j[2]),
                     lambda a, p, s: {"base": base, "arm": a, "point": p, "seed": s, "gamma": args.gamma,
                                      "keep": args.keep, "rolling_eta": args.rolling_eta},
                     run_one, COLUMNS, summary, extra=lambda row: f"Bo {number(row.get('bond_number')):.2f}")
    if args.correction:
        corr = density_correction(rows)
        write_text_atomically(Path(args.correction), json.dumps(corr, indent=1, default=float) + "\n")
        print(json.dumps(corr["config_block"], indent=1))


if __name__ == "__main__":
    main()
